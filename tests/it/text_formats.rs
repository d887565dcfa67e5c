//! Text trajectory formats on real files (evo's test data in `shared/evo-data`): every reader keeps the
//! row count of its file (REFERENCE.md), the format is picked from the file alone, and a CSV mapping
//! that names a missing column fails with a one-line error.

use crate::common;

use trajdrift::sources::mapped_csv::CsvMapping;
use trajdrift::sources::text::{detect_format, read_text, TextFormat, TextOptions};

#[test]
fn evo_files_read_with_the_row_counts_of_the_files() {
    let Some(shared) = common::shared() else {
        return;
    };
    let evo = shared.join("evo-data");
    let times = evo.join("KITTI_00_gt_times.txt");
    let cases = [
        ("fr2_desk_groundtruth.txt", TextFormat::Tum, 20957, true),
        ("fr2_desk_ORB.txt", TextFormat::Tum, 2893, true),
        ("freiburg1_xyz-groundtruth.txt", TextFormat::Tum, 3000, true),
        ("freiburg1_xyz-rgbdslam.txt", TextFormat::Tum, 788, true),
        ("KITTI_00_gt.txt", TextFormat::Kitti, 4541, true),
        ("KITTI_00_ORB.txt", TextFormat::Kitti, 4541, true),
        ("KITTI_00_SPTAM.txt", TextFormat::Kitti, 4541, true),
        ("V102_groundtruth.csv", TextFormat::Euroc, 16702, true),
        ("V102.txt", TextFormat::Tum, 807, true),
    ];
    let options = TextOptions {
        kitti_times: Some(times.clone()),
        ..TextOptions::default()
    };
    for (file, format, rows, oriented) in cases {
        let path = evo.join(file);
        assert_eq!(detect_format(&path).unwrap(), format, "{file}");
        let (t, f) = read_text(&path, &options).unwrap();
        assert_eq!(f, format);
        // fr2_desk_groundtruth repeats one stamp and V102.txt four (same first field on two rows):
        // every source keeps one sample per stamp.
        let text = std::fs::read_to_string(&path).unwrap();
        let data: Vec<&str> = text
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
            .collect();
        assert_eq!(data.len(), rows, "{file}: rows of the file");
        let repeated = if format == TextFormat::Kitti {
            0
        } else {
            let firsts: std::collections::BTreeSet<&str> = data
                .iter()
                .map(|l| l.split([' ', ',']).next().unwrap())
                .collect();
            rows - firsts.len()
        };
        assert_eq!(t.len() + repeated, rows, "{file}");
        assert_eq!(t.orientations.is_some(), oriented, "{file}");
    }
    // KITTI stamps come from the times file: the last one is its last row.
    let (kitti, _) = read_text(&evo.join("KITTI_00_gt.txt"), &options).unwrap();
    let last = std::fs::read_to_string(&times).unwrap();
    let last: f64 = last.lines().last().unwrap().trim().parse().unwrap();
    assert!((*kitti.stamps_ns.last().unwrap() as f64 * 1e-9 - last).abs() < 1e-6);
    // The EuRoC file read through an explicit CSV mapping gives the same trajectory.
    let csv = TextOptions {
        format: Some(TextFormat::Csv),
        csv: Some(
            CsvMapping::parse(
                "t=timestamp:ns,x=p_RS_R_x,y=p_RS_R_y,z=p_RS_R_z,qx=q_RS_x,qy=q_RS_y,qz=q_RS_z,qw=q_RS_w",
            )
            .unwrap(),
        ),
        ..TextOptions::default()
    };
    let (a, _) = read_text(&evo.join("V102_groundtruth.csv"), &csv).unwrap();
    let (b, _) = read_text(&evo.join("V102_groundtruth.csv"), &options).unwrap();
    assert_eq!(a, b);
}

#[test]
fn a_csv_mapping_naming_a_missing_column_is_a_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("odom.csv");
    std::fs::write(&path, "stamp,px,py,pz\n1,0,0,0\n2,1,0,0\n").unwrap();
    let options = TextOptions {
        csv: Some(CsvMapping::parse("t=stamp:us,x=px,y=py,z=height").unwrap()),
        ..TextOptions::default()
    };
    let e = read_text(&path, &options).unwrap_err().to_string();
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains("odom.csv") && e.contains("`height`") && e.contains("stamp, px, py, pz"));
    // Without a mapping the columns must be named t, x, y, z.
    let e = read_text(&path, &TextOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("--csv"), "{e}");
}

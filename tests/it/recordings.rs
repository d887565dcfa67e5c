//! Every recording format gives the same trajectories: MCAP, ROS 1 bags (none/bz2/lz4 chunks),
//! ROS 1 in MCAP, rosbag2 folders (mcap and sqlite3), plus the evo data counts and the errors.

use crate::common;
use crate::hostile_support::{BagShape, EstimateMsg};

use std::path::{Path, PathBuf};

use trajdrift::evaluate;
use trajdrift::params::Platform;
use trajdrift::sources::bag::writer::BagCompression;
use trajdrift::sources::{open, ExtractOptions, Extraction};
use trajdrift::{EvalConfig, NamedInput};

use common::{mission, shared, MISSIONS};

const TOPICS: [&str; 4] = [
    "/reference/position",
    "/reference/fix",
    "/estimate/odom",
    "/estimate/pose",
];

fn extract(path: &Path, topics: &[&str]) -> Extraction {
    let topics: Vec<String> = topics.iter().map(|s| s.to_string()).collect();
    open(path)
        .and_then(|s| s.extract(&topics, &ExtractOptions::default(), &|_| {}))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn assert_same(a: &Extraction, b: &Extraction, what: &str) {
    assert_eq!(a.topics.len(), b.topics.len());
    for (x, y) in a.topics.iter().zip(&b.topics) {
        assert_eq!(
            x.trajectory.stamps_ns, y.trajectory.stamps_ns,
            "{what} {}",
            x.topic
        );
        assert_eq!(
            x.trajectory.positions, y.trajectory.positions,
            "{what} {}",
            x.topic
        );
        assert_eq!(
            x.trajectory.orientations, y.trajectory.orientations,
            "{what} {}",
            x.topic
        );
        assert_eq!(x.geodetic_origin, y.geodetic_origin, "{what} {}", x.topic);
    }
}

fn forms(dir: &Path) -> Vec<PathBuf> {
    [dir.join("rosbag2"), dir.join("mission_ros1.bag")]
        .into_iter()
        .filter(|p| p.exists())
        .collect()
}

#[test]
fn every_form_of_a_mission_gives_bit_identical_trajectories() {
    let Some(shared) = shared() else { return };
    for m in MISSIONS {
        let dir = mission(&shared, m);
        let base = extract(&dir.join("mission.mcap"), &TOPICS);
        assert!(base.topics.iter().all(|t| !t.trajectory.is_empty()));
        for f in forms(&dir) {
            assert_same(&base, &extract(&f, &TOPICS), &f.display().to_string());
        }
    }
}

#[test]
fn every_form_of_a_mission_gives_the_same_eval() {
    let Some(shared) = shared() else { return };
    // One mission per storage: mcap rosbag2 + lz4 bag, sqlite3 rosbag2, bz2 bag.
    for m in ["lever_arm", "gnss_outages", "legged"] {
        let dir = mission(&shared, m);
        let run = |rec: PathBuf| {
            let mut c = EvalConfig::new(
                Some(rec.clone()),
                NamedInput::topic("/reference/position"),
                vec![NamedInput::topic("/estimate/odom")],
            );
            c.params.platform = Some(Platform::Wheeled);
            let r = evaluate(&c).unwrap_or_else(|e| panic!("{e}"));
            serde_json::to_value((&r.reference, &r.estimates, &r.warnings)).unwrap()
        };
        let base = run(dir.join("mission.mcap"));
        for f in forms(&dir) {
            assert_eq!(base, run(f.clone()), "{}", f.display());
        }
    }
}

#[test]
fn evo_data_counts() {
    let Some(shared) = shared() else { return };
    let evo = shared.join("evo-data");
    let counts = |p: &Path| -> Vec<(String, u64)> {
        open(p)
            .and_then(|s| s.topics())
            .unwrap()
            .into_iter()
            .map(|t| (t.topic, t.message_count))
            .collect()
    };
    let bag = evo.join("ROS_example.bag");
    let c = counts(&bag);
    for (t, n) in [("groundtruth", 12765), ("ORB-SLAM", 8362), ("S-PTAM", 5439)] {
        assert!(c.contains(&(t.to_string(), n)), "{t}: {c:?}");
    }
    let ex = extract(&bag, &["groundtruth", "ORB-SLAM", "S-PTAM"]);
    let n: Vec<u64> = ex.topics.iter().map(|t| t.messages).collect();
    assert_eq!(n, [12765, 8362, 5439]);

    let nav2 = evo.join("nav2_turtlebot.mcap");
    let ex = extract(&nav2, &["/odom", "/amcl_pose"]);
    let n: Vec<u64> = ex.topics.iter().map(|t| t.messages).collect();
    assert_eq!(n, [2639, 135]);
    assert!(counts(&nav2).contains(&("/tf".to_string(), 5422)));
}

/// A small ROS 1 bag with a reference and an estimate (odometry and pose), in `compression`.
fn write_bag(path: &Path, compression: BagCompression, n: u32) {
    BagShape {
        compression,
        n,
        period_ns: 10_000_000,
        wave_rad: 0.01,
        chunk_bytes: 4096,
        estimates: &[
            ("/estimate/odom", EstimateMsg::Odometry),
            ("/estimate/pose", EstimateMsg::Pose),
        ],
        ..Default::default()
    }
    .write(path);
}

#[test]
fn written_bags_read_back_in_every_compression() {
    let dir = tempfile::tempdir().unwrap();
    let topics = ["/reference/position", "/estimate/odom", "/estimate/pose"];
    let mut first: Option<Extraction> = None;
    for (name, c) in [
        ("none", BagCompression::None),
        ("bz2", BagCompression::Bz2),
        ("lz4", BagCompression::Lz4),
    ] {
        let p = dir.path().join(format!("{name}.bag"));
        write_bag(&p, c, 500);
        let ex = extract(&p, &topics);
        assert_eq!(ex.topics[0].trajectory.len(), 500, "{name}");
        assert_eq!(ex.topics[1].trajectory.positions[7].x, 0.7000000000000001);
        let t = open(&p).unwrap().topics().unwrap();
        assert_eq!(t.len(), 3);
        assert!(t.iter().all(|t| t.message_count == 500 && t.readable));
        match &first {
            Some(f) => assert_same(f, &ex, name),
            None => first = Some(ex),
        }
    }
}

#[test]
fn ros1_in_mcap_reads_like_the_bag() {
    let Some(shared) = shared() else { return };
    let bag = mission(&shared, "lever_arm").join("mission_ros1.bag");
    let from_bag = extract(&bag, &TOPICS);
    // Copy the bag's messages into an MCAP with profile ros1 (ros1msg schemas, ros1 messages).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ros1.mcap");
    {
        use trajdrift::sources::bag::BagSource;
        use trajdrift::sources::recording::Recording;
        let source = BagSource::open(&bag).unwrap();
        let f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut w = mcap::WriteOptions::new().profile("ros1").create(f).unwrap();
        let mut ids = std::collections::HashMap::new();
        source
            .pass(
                &mut |c| TOPICS.contains(&c.topic.as_str()),
                &|_| {},
                &mut |c, m| {
                    let id = *ids.entry(c.id).or_insert_with(|| {
                        let s = w.add_schema(&c.schema_name, "ros1msg", b"").unwrap();
                        w.add_channel(s, &c.topic, "ros1", &Default::default())
                            .unwrap()
                    });
                    let header = mcap::records::MessageHeader {
                        channel_id: id,
                        sequence: 0,
                        log_time: m.log_time,
                        publish_time: m.publish_time,
                    };
                    w.write_to_known_channel(&header, m.data).unwrap();
                    Ok(())
                },
            )
            .unwrap();
        w.finish().unwrap();
    }
    let t = open(&path).unwrap().topics().unwrap();
    assert!(t.iter().all(|t| t.readable && t.message_encoding == "ros1"));
    assert_same(&from_bag, &extract(&path, &TOPICS), "ros1 mcap");
}

#[test]
fn unknown_bag_compression_is_a_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("zstd.bag");
    write_bag(&p, BagCompression::Other("zstd".into()), 10);
    let err = open(&p)
        .and_then(|s| {
            s.extract(
                &["/estimate/odom".into()],
                &ExtractOptions::default(),
                &|_| {},
            )
        })
        .err()
        .unwrap()
        .to_string();
    assert!(!err.contains('\n'));
    assert!(
        err.contains("zstd.bag") && err.contains("compression `zstd`"),
        "{err}"
    );
    assert!(err.contains("rosbag decompress"), "{err}");
}

#[test]
fn rosbag2_folder_with_a_missing_file_is_a_one_line_error() {
    let Some(shared) = shared() else { return };
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        mission(&shared, "lever_arm").join("rosbag2/metadata.yaml"),
        dir.path().join("metadata.yaml"),
    )
    .unwrap();
    let err = open(dir.path()).err().unwrap().to_string();
    assert!(!err.contains('\n'));
    assert!(err.contains("rosbag2.mcap, which is missing"), "{err}");
    // The same without shared data: a metadata.yaml written here.
    let dir2 = tempfile::tempdir().unwrap();
    std::fs::write(
        dir2.path().join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths: [a_0.db3]\n",
    )
    .unwrap();
    let err = open(dir2.path()).err().unwrap().to_string();
    assert!(
        err.contains("a_0.db3, which is missing") && !err.contains('\n'),
        "{err}"
    );
}

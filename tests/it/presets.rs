//! Presets as a user meets them: `eval --preset grandtour` on GrandTour-like bags (newer `/boxi` and
//! older `/gt_box` topic names), `--preset fomo` with FoMo's position-only `gt.txt` as reference,
//! `topics` naming the matching preset, a user's preset file, a batch manifest with a preset, and the
//! one-line errors. Recordings are written here from the project's simulator with the datasets' topic
//! names.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use trajdrift::decode::cdr::encode_le;
use trajdrift::decode::ros1;
use trajdrift::decode::ros2_msgs::{Header, Odometry, Point, PointStamped, Time};
use trajdrift::decode::ros2_schemas::schema_text;
use trajdrift::simulate::{default_route, simulate, Mission, MissionConfig};
use trajdrift::sources::bag::writer::{BagCompression, BagWriter};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(args)
        .output()
        .expect("run trajdrift")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn mission() -> Mission {
    simulate(&MissionConfig::default(), &default_route())
}

fn header(ns: i64) -> Header {
    Header {
        stamp: Time::from_ns(ns),
        frame_id: "map".into(),
    }
}

fn odometry(ns: i64, p: &nalgebra::Vector3<f64>) -> Odometry {
    let mut o = Odometry {
        header: header(ns),
        ..Default::default()
    };
    o.pose.pose.position = Point {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    o
}

/// A ROS 1 bag with GrandTour's topics under `prefix` (`/boxi` or `/gt_box`): the INS as reference,
/// DLIO and the ANYmal state estimator as estimates, and the prism position when asked.
fn grandtour_bag(dir: &Path, prefix: &str, prism: bool) -> PathBuf {
    let m = mission();
    let path = dir.join(format!("grandtour{}.bag", prefix.replace('/', "_")));
    let f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let mut w = BagWriter::new(f, BagCompression::Lz4, 64 * 1024).unwrap();
    let ins = w.add_connection(
        &format!("{prefix}/inertial_explorer/tc/odometry"),
        "nav_msgs/Odometry",
    );
    let dlio = w.add_connection(
        &format!("{prefix}/dlio/lidar_map_odometry"),
        "nav_msgs/Odometry",
    );
    let anymal = w.add_connection("/anymal/state_estimator/odometry", "nav_msgs/Odometry");
    let ap20 = prism.then(|| {
        w.add_connection(
            &format!("{prefix}/ap20/prism_position"),
            "geometry_msgs/PointStamped",
        )
    });
    let mut events: Vec<(i64, u32, Vec<u8>)> = Vec::new();
    for (i, (&t, p)) in m
        .reference
        .stamps_ns
        .iter()
        .zip(&m.reference.positions)
        .enumerate()
    {
        events.push((t, ins, ros1::encode_odometry(i as u32, &odometry(t, p))));
        if let Some(c) = ap20 {
            let ps = PointStamped {
                header: header(t),
                point: Point {
                    x: p.x,
                    y: p.y,
                    z: p.z,
                },
            };
            events.push((t, c, ros1::encode_point_stamped(i as u32, &ps)));
        }
    }
    for (i, (&t, p)) in m
        .estimate
        .stamps_ns
        .iter()
        .zip(&m.estimate.positions)
        .enumerate()
    {
        let data = ros1::encode_odometry(i as u32, &odometry(t, p));
        events.push((t, dlio, data.clone()));
        events.push((t, anymal, data));
    }
    events.sort_by_key(|e| (e.0, e.1));
    for (t, c, data) in events {
        w.write(c, t as u64, &data).unwrap();
    }
    w.finish().unwrap();
    path
}

/// A ROS 2 MCAP with FoMo's wheel odometry, and FoMo's GNSS reference as a position-only TUM file
/// (`t x y z`), gt.txt.
fn fomo(dir: &Path) -> (PathBuf, PathBuf) {
    let m = mission();
    let path = dir.join("fomo.mcap");
    let f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    let mut w = mcap::WriteOptions::new().profile("ros2").create(f).unwrap();
    let ty = "nav_msgs/msg/Odometry";
    let schema = w
        .add_schema(ty, "ros2msg", schema_text(ty).unwrap().as_bytes())
        .unwrap();
    let ch = w
        .add_channel(schema, "/warthog/platform/odom", "cdr", &BTreeMap::new())
        .unwrap();
    for (i, (&t, p)) in m
        .estimate
        .stamps_ns
        .iter()
        .zip(&m.estimate.positions)
        .enumerate()
    {
        let header = mcap::records::MessageHeader {
            channel_id: ch,
            sequence: i as u32,
            log_time: t as u64,
            publish_time: t as u64,
        };
        w.write_to_known_channel(&header, &encode_le(&odometry(t, p)))
            .unwrap();
    }
    w.finish().unwrap();
    let gt = dir.join("gt.txt");
    let text: String = m
        .reference
        .stamps_ns
        .iter()
        .zip(&m.reference.positions)
        .map(|(t, p)| format!("{:.9} {} {} {}\n", *t as f64 * 1e-9, p.x, p.y, p.z))
        .collect();
    std::fs::write(&gt, text).unwrap();
    (path, gt)
}

/// Runs eval and returns the JSON report (exit 0, or 3 for a warning).
fn eval_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["eval", "--quiet", "--json", "-"];
    all.extend_from_slice(args);
    let o = run(&all);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{args:?}: {}",
        stderr(&o)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

fn estimates(report: &serde_json::Value) -> Vec<(String, String)> {
    report["estimates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["name"].as_str().unwrap().to_string(),
                e["topic"].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

#[test]
fn grandtour_preset_reads_new_and_old_topic_names() {
    let dir = tempfile::tempdir().unwrap();
    for prefix in ["/boxi", "/gt_box"] {
        let bag = grandtour_bag(dir.path(), prefix, false);
        let r = eval_json(&[s(&bag), "--preset", "grandtour"]);
        assert_eq!(
            r["reference"]["topic"],
            format!("{prefix}/inertial_explorer/tc/odometry")
        );
        assert_eq!(
            estimates(&r),
            vec![
                ("dlio".into(), format!("{prefix}/dlio/lidar_map_odometry")),
                (
                    "state_estimator".into(),
                    "/anymal/state_estimator/odometry".into()
                ),
            ]
        );
        // The simulator's estimate clock is 0.2 s off the reference's.
        let dt = r["estimates"][0]["time_offset"]["applied_s"]
            .as_f64()
            .unwrap();
        assert!((dt - 0.2).abs() < 0.03, "{prefix}: {dt}");
    }
}

#[test]
fn flags_replace_the_presets_topics_and_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let bag = grandtour_bag(dir.path(), "/boxi", true);
    let r = eval_json(&[
        s(&bag),
        "--preset",
        "grandtour",
        "--reference",
        "/boxi/ap20/prism_position",
        "--estimate",
        "lio=/boxi/dlio/lidar_map_odometry",
        "--window",
        "7",
    ]);
    assert_eq!(r["reference"]["topic"], "/boxi/ap20/prism_position");
    assert_eq!(
        estimates(&r),
        vec![("lio".into(), "/boxi/dlio/lidar_map_odometry".into())]
    );
    // A user's preset file: its parameters apply unless a flag is given.
    let user = dir.path().join("mine.toml");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/presets/grandtour-prism.toml"
    ))
    .unwrap()
    .replace("name = \"grandtour-prism\"", "name = \"mine\"")
    .replace(
        "# window = [5, 10]",
        "window = [3, 6]\nplatform = \"legged\"",
    );
    std::fs::write(&user, text).unwrap();
    let r = eval_json(&[s(&bag), "--preset", s(&user), "--platform", "auto"]);
    assert_eq!(r["reference"]["topic"], "/boxi/ap20/prism_position");
    assert_eq!(r["parameters"]["windows_m"], serde_json::json!([3.0, 6.0]));
    assert_eq!(r["parameters"]["platform"], "auto");
}

#[test]
fn topics_names_the_matching_presets() {
    let dir = tempfile::tempdir().unwrap();
    let bag = grandtour_bag(dir.path(), "/gt_box", true);
    let o = run(&["topics", s(&bag)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("presets matching: grandtour, grandtour-prism"),
        "{out}"
    );
    let o = run(&["topics", s(&bag), "--json", "-"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        v["presets"],
        serde_json::json!(["grandtour", "grandtour-prism"])
    );
    assert_eq!(v["topics"].as_array().unwrap().len(), 4);

    let (mcap, _) = fomo(dir.path());
    let o = run(&["topics", s(&mcap), "--json", "-"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["presets"], serde_json::json!(["fomo"]));
}

#[test]
fn fomo_preset_with_the_gnss_reference_file() {
    let dir = tempfile::tempdir().unwrap();
    let (mcap, gt) = fomo(dir.path());
    let r = eval_json(&[s(&mcap), "--preset", "fomo", "--reference-file", s(&gt)]);
    assert_eq!(
        estimates(&r),
        vec![("warthog_odom".into(), "/warthog/platform/odom".into())]
    );
    assert!(r["reference"]["topic"]
        .as_str()
        .unwrap()
        .ends_with("gt.txt"));
    // Without the file: one line saying to give it.
    let o = run(&["eval", s(&mcap), "--preset", "fomo"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("--reference-file gt.txt"), "{e}");
}

#[test]
fn preset_errors_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let (mcap, _) = fomo(dir.path());
    // The recording lacks the preset's reference.
    let o = run(&["eval", s(&mcap), "--preset", "grandtour"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    for part in [
        "fomo.mcap",
        "preset grandtour",
        "/boxi/inertial_explorer/tc/odometry or /gt_box/inertial_explorer/tc/odometry",
        "--reference TOPIC",
    ] {
        assert!(e.contains(part), "{part}: {e}");
    }
    // An unknown name lists the known ones.
    let o = run(&["eval", s(&mcap), "--preset", "kitti"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("grandtour, grandtour-prism, fomo"), "{e}");
    // A broken preset file names itself.
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "name = \"x\"\nrefrence = 1\n").unwrap();
    let o = run(&["eval", s(&mcap), "--preset", s(&bad)]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("bad.toml") && e.contains("refrence"), "{e}");
}

#[test]
fn batch_manifest_takes_a_preset_in_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let new = grandtour_bag(dir.path(), "/boxi", false);
    let old = grandtour_bag(dir.path(), "/gt_box", false);
    let manifest = dir.path().join("m.toml");
    std::fs::write(
        &manifest,
        format!(
            "[defaults]\npreset = \"grandtour\"\n\n[[mission]]\nrecording = \"{}\"\n\n[[mission]]\nrecording = \"{}\"\nestimates = [\"/anymal/state_estimator/odometry\"]\n",
            new.file_name().unwrap().to_str().unwrap(),
            old.file_name().unwrap().to_str().unwrap()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = run(&[
        "batch",
        s(&manifest),
        "--quiet",
        "--out",
        s(&out),
        "-j",
        "1",
    ]);
    assert!(matches!(o.status.code(), Some(0 | 3)), "{}", stderr(&o));
    let old_result: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("grandtour_gt_box.json")).unwrap()).unwrap();
    let report = &old_result["report"];
    assert_eq!(
        report["reference"]["topic"],
        "/gt_box/inertial_explorer/tc/odometry"
    );
    assert_eq!(report["estimates"].as_array().unwrap().len(), 1);
    let new_result: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("grandtour_boxi.json")).unwrap()).unwrap();
    assert_eq!(
        new_result["report"]["estimates"].as_array().unwrap().len(),
        2
    );
}

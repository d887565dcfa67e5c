//! Missions of several recordings: a GrandTour-like mission written by our simulator as
//! per-sensor ROS 1 bags evaluates from its files, from its folder, with the GrandTour presets and
//! with a TF chain across bags, giving the report one merged bag of the same messages gives; its
//! `--annotate` output holds every input message; `topics` names the presets; a topic with two types
//! is refused; batch finds missions in a folder.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;
use trajdrift::simulate::grandtour::{write_grandtour, GrandTourOptions, DLIO_TF_CHAIN};
use trajdrift::simulate::{default_route, simulate, MissionConfig};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(args)
        .output()
        .expect("run trajdrift")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The mission as its 5 bags in `dir/split`, and merged into one bag in `dir/merged`.
fn mission(dir: &Path) -> (Vec<PathBuf>, PathBuf) {
    let m = simulate(&MissionConfig::default(), &default_route());
    let files = write_grandtour(&dir.join("split"), &m, &GrandTourOptions::default()).unwrap();
    let merged = write_grandtour(
        &dir.join("merged"),
        &m,
        &GrandTourOptions {
            merged: true,
            ..GrandTourOptions::default()
        },
    )
    .unwrap();
    assert_eq!(files.len(), 5);
    (files, merged[0].clone())
}

/// Runs `eval INPUTS ARGS --json`; returns the report without `input` (its path and size name the
/// files, which differ by design).
fn report(dir: &Path, inputs: &[&Path], args: &[&str], name: &str) -> Value {
    let json = dir.join(format!("{name}.json"));
    let mut all: Vec<&str> = vec!["eval", "--quiet"];
    all.extend(inputs.iter().map(|p| s(p)));
    all.extend(args);
    all.extend(["--json", s(&json)]);
    let o = run(&all);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let mut v: Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("input");
    v
}

#[test]
fn a_mission_in_many_bags_reports_what_one_merged_bag_reports() {
    let dir = tempfile::tempdir().unwrap();
    let (files, merged) = mission(dir.path());
    let split = dir.path().join("split");
    let file_refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let chain_args = [
        "--reference",
        "/boxi/ap20/prism_position",
        "--estimate",
        &format!("dlio_tf={DLIO_TF_CHAIN}"),
        "--estimate",
        "dlio=/boxi/dlio/lidar_map_odometry",
        "--estimate-lever",
        "dlio=tf-static:base:hesai_lidar",
        "--estimate-lever",
        "dlio_tf=tf-static:base:hesai_lidar",
        "--estimate",
        "state=/anymal/state_estimator/odometry",
    ];
    // Plain topics in three bags and no TF: the bags are read side by side, each on its own (one
    // topic asked for twice).
    let side_by_side = [
        "--reference",
        "/boxi/ap20/prism_position",
        "--estimate",
        "/boxi/dlio/lidar_map_odometry",
        "--estimate",
        "/anymal/state_estimator/odometry",
        "--estimate",
        "again=/boxi/dlio/lidar_map_odometry",
    ];
    let cases: [(&str, Vec<&Path>, Vec<&str>); 5] = [
        ("side_by_side", vec![split.as_path()], side_by_side.to_vec()),
        (
            "files",
            file_refs.clone(),
            vec!["--preset", "grandtour-prism"],
        ),
        (
            "folder",
            vec![split.as_path()],
            vec!["--preset", "grandtour-prism"],
        ),
        ("ins", vec![split.as_path()], vec!["--preset", "grandtour"]),
        ("tf_chain", file_refs.clone(), chain_args.to_vec()),
    ];
    for (name, inputs, args) in cases {
        let one = report(dir.path(), &inputs, &args, name);
        let reference = report(dir.path(), &[&merged], &args, &format!("{name}-merged"));
        assert_eq!(
            one, reference,
            "{name}: the mission and the merged bag differ"
        );
        assert!(
            one["estimates"].as_array().unwrap().len() >= 2,
            "{name}: {one}"
        );
        println!(
            "{name}: report equal to the merged bag's ({} estimates; first Δt {} s, DE RMSE {} )",
            one["estimates"].as_array().unwrap().len(),
            one["estimates"][0]["time_offset"]["applied_s"],
            one["estimates"][0]["drift_error"][0]["rmse"]
        );
    }
    // The chain across two bags is the DLIO pose again.
    let r = report(dir.path(), &file_refs, &chain_args, "tf_chain_again");
    let e = r["estimates"].as_array().unwrap();
    let dt = |i: usize| e[i]["time_offset"]["applied_s"].as_f64().unwrap();
    assert!(
        (dt(0) - dt(1)).abs() < 1e-6,
        "chain {} vs topic {}",
        dt(0),
        dt(1)
    );
}

#[test]
fn annotate_a_mission_keeps_every_message_of_every_bag() {
    let dir = tempfile::tempdir().unwrap();
    let (_, _) = mission(dir.path());
    let split = dir.path().join("split");
    let out = dir.path().join("annotated.mcap");
    let o = run(&[
        "eval",
        "--quiet",
        s(&split),
        "--preset",
        "grandtour-prism",
        "--annotate",
        s(&out),
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let input = trajdrift::sources::open(&split).unwrap().topics().unwrap();
    let output = trajdrift::sources::open(&out).unwrap().topics().unwrap();
    for t in &input {
        let got = output.iter().find(|o| o.topic == t.topic);
        assert_eq!(
            got.map(|o| (o.message_count, o.message_encoding.as_str())),
            Some((t.message_count, "ros1")),
            "{}",
            t.topic
        );
    }
    let new: Vec<&str> = output
        .iter()
        .filter(|o| o.topic.starts_with("/trajdrift/"))
        .map(|o| o.topic.as_str())
        .collect();
    for want in [
        "/trajdrift/reference/curvature",
        "/trajdrift/dlio/aligned",
        "/trajdrift/dlio/drift_error",
        "/trajdrift/state_estimator/aligned",
    ] {
        assert!(new.contains(&want), "{want} missing from {new:?}");
    }
    let total: u64 = input.iter().map(|t| t.message_count).sum();
    println!(
        "annotated mission: {total} input messages on {} topics, counts per topic equal; {} trajdrift channels",
        input.len(),
        new.len()
    );
}

#[test]
fn annotate_is_refused_before_the_evaluation() {
    let dir = tempfile::tempdir().unwrap();
    let (files, _) = mission(dir.path());
    let split = dir.path().join("split");
    // Over an input.
    let o = run(&[
        "eval",
        s(&files[0]),
        s(&files[1]),
        s(&files[2]),
        s(&files[3]),
        s(&files[4]),
        "--preset",
        "grandtour",
        "--annotate",
        s(&files[0]),
        "--force",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("would destroy the input"));
    // Inside the mission folder (a new file there would join the mission).
    let o = run(&[
        "eval",
        s(&split),
        "--preset",
        "grandtour",
        "--annotate",
        s(&split.join("out.mcap")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("inside the input folder"));
}

#[test]
fn topics_of_a_mission_folder_name_the_presets_and_the_files() {
    let dir = tempfile::tempdir().unwrap();
    let (_, _) = mission(dir.path());
    let o = run(&["topics", s(&dir.path().join("split"))]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("presets matching: grandtour, grandtour-prism"),
        "{text}"
    );
    assert!(text.contains("_tf_minimal.bag: /tf_static"), "{text}");
    assert!(text.contains("/tf:dlio_map:hesai_lidar"), "{text}");
}

#[test]
fn one_topic_with_two_types_in_two_files_is_a_clear_error() {
    use trajdrift::decode::ros1;
    use trajdrift::decode::ros2_msgs::{PointStamped, PoseStamped};
    use trajdrift::sources::bag::writer::{BagCompression, BagWriter};
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, ty: &str, data: &dyn Fn(u32) -> Vec<u8>| {
        let path = dir.path().join(name);
        let f = std::fs::File::create(&path).unwrap();
        let mut w = BagWriter::new(f, BagCompression::None, 1 << 16).unwrap();
        let c = w.add_connection("/pose", ty);
        for i in 0..10 {
            w.write(c, 1_000_000_000 + u64::from(i), &data(i)).unwrap();
        }
        w.finish().unwrap();
        path
    };
    let a = write("a.bag", "geometry_msgs/PoseStamped", &|i| {
        ros1::encode_pose_stamped(i, &PoseStamped::default())
    });
    let b = write("b.bag", "geometry_msgs/PointStamped", &|i| {
        ros1::encode_point_stamped(i, &PointStamped::default())
    });
    let o = run(&["export", s(&a), s(&b), "--topic", "/pose", "-"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("/pose has type") && err.contains("a.bag") && err.contains("b.bag"),
        "{err}"
    );
}

#[test]
fn batch_takes_mission_folders_bags_and_rosbag2_folders() {
    let dir = tempfile::tempdir().unwrap();
    let (_, merged) = mission(dir.path());
    let missions = dir.path().join("missions");
    std::fs::create_dir(&missions).unwrap();
    std::fs::rename(dir.path().join("split"), missions.join("gt")).unwrap();
    std::fs::rename(&merged, missions.join("merged.bag")).unwrap();
    let out = dir.path().join("out");
    let o = run(&[
        "batch",
        s(&missions),
        "--reference",
        "/boxi/ap20/prism_position",
        "--estimate",
        "/boxi/dlio/lidar_map_odometry",
        "--out",
        s(&out),
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let load = |n: &str| -> Value {
        serde_json::from_slice(&std::fs::read(out.join(format!("{n}.json"))).unwrap()).unwrap()
    };
    let (gt, one) = (load("gt"), load("merged"));
    assert_eq!(gt["status"], "ok", "{gt}");
    assert!(gt["report"]["estimates"][0]["drift_error"][0]["rmse"].is_number());
    assert_eq!(
        gt["report"]["estimates"], one["report"]["estimates"],
        "the mission folder and the merged bag differ"
    );
}

#[test]
fn a_topic_split_over_two_files_is_merged_by_stamp() {
    use trajdrift::decode::ros1;
    use trajdrift::decode::ros2_msgs::{Header, PointStamped, Time};
    use trajdrift::sources::bag::writer::{BagCompression, BagWriter};
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, keep: &dyn Fn(u32) -> bool| {
        let path = dir.path().join(name);
        let f = std::fs::File::create(&path).unwrap();
        let mut w = BagWriter::new(f, BagCompression::None, 1 << 12).unwrap();
        let c = w.add_connection("/p", "geometry_msgs/PointStamped");
        for i in (0..200u32).filter(|&i| keep(i)) {
            let t = 1_700_000_000_000_000_000 + u64::from(i) * 50_000_000;
            let mut m = PointStamped {
                header: Header {
                    stamp: Time::from_ns(t as i64),
                    frame_id: "map".into(),
                },
                ..Default::default()
            };
            m.point.x = f64::from(i);
            m.point.y = f64::from(i).sin();
            w.write(c, t, &ros1::encode_point_stamped(i, &m)).unwrap();
        }
        w.finish().unwrap();
        path
    };
    let odd = write("odd.bag", &|i| i % 2 == 1);
    let even = write("even.bag", &|i| i % 2 == 0);
    let all = write("all.bag", &|_| true);
    let export = |inputs: &[&Path], out: &str| {
        let out = dir.path().join(out);
        let mut args = vec!["export"];
        args.extend(inputs.iter().map(|p| s(p)));
        args.extend(["--topic", "/p", s(&out)]);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(out).unwrap()
    };
    let merged = export(&[&odd, &even], "merged.tum");
    assert_eq!(merged.lines().count(), 200);
    assert_eq!(merged, export(&[&all], "all.tum"));
}

#[test]
fn annotate_from_text_trajectories_writes_the_trajdrift_channels() {
    let dir = tempfile::tempdir().unwrap();
    let (_, _) = mission(dir.path());
    let split = dir.path().join("split");
    let tum = |topic: &str, name: &str| {
        let out = dir.path().join(name);
        let o = run(&["export", s(&split), "--topic", topic, s(&out)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let reference = tum("/boxi/ap20/prism_position", "prism.tum");
    let estimate = tum("/boxi/dlio/lidar_map_odometry", "dlio.tum");
    let out = dir.path().join("text.mcap");
    let o = run(&[
        "eval",
        "--quiet",
        "--reference-file",
        s(&reference),
        "--estimate-file",
        &format!("dlio={}", s(&estimate)),
        "--annotate",
        s(&out),
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let topics = trajdrift::sources::open(&out).unwrap().topics().unwrap();
    let aligned = topics
        .iter()
        .find(|t| t.topic == "/trajdrift/dlio/aligned")
        .expect("aligned channel");
    assert_eq!(aligned.type_name, "geometry_msgs/msg/PoseStamped");
    assert_eq!(
        aligned.message_count,
        std::fs::read_to_string(&estimate).unwrap().lines().count() as u64
    );
    assert!(topics.iter().all(|t| t.topic.starts_with("/trajdrift/")));
}

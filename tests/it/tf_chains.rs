//! TF chains (`/tf:PARENT:CHILD`) and `tf-static:` levers, on data written by other tools (the shared
//! fixtures, evo's nav2 turtlebot MCAP) and on small recordings written here with the mcap crate.

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use trajdrift::decode::cdr::encode_le;
use trajdrift::decode::ros2_msgs::{PointStamped, TFMessage, Time, TransformStamped};
use trajdrift::evaluate;
use trajdrift::simulate::{default_route, simulate, MissionConfig};
use trajdrift::sources::{open, ExtractOptions, Extraction};
use trajdrift::trajectory::Trajectory;
use trajdrift::{EvalConfig, LeverSpec, NamedInput};

fn extract(path: &Path, topics: &[&str], options: &ExtractOptions) -> Extraction {
    let topics: Vec<String> = topics.iter().map(|t| t.to_string()).collect();
    open(path)
        .unwrap()
        .extract(&topics, options, &|_| {})
        .unwrap_or_else(|e| panic!("{e}"))
}

fn pose(t: &Trajectory, i: usize) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(t.positions[i]),
        t.orientations.as_ref().unwrap()[i],
    )
}

/// `/tf:odom:base_link` is `/estimate/odom` sample for sample: same stamps, bit-identical positions
/// and quaternions (the simulator wrote the same numbers to both; a one-edge chain is its messages).
#[test]
fn odom_chain_equals_the_odometry_in_every_fixture_and_format() {
    let Some(shared) = common::shared() else {
        return;
    };
    let mut checked = Vec::new();
    for name in common::MISSIONS {
        let dir = common::mission(&shared, name);
        for rec in [
            dir.join("mission.mcap"),
            dir.join("mission_ros1.bag"),
            dir.join("rosbag2"),
        ] {
            if !rec.exists() {
                continue;
            }
            let ex = extract(
                &rec,
                &["/tf:odom:base_link", "/estimate/odom"],
                &ExtractOptions::default(),
            );
            let (chain, odom) = (&ex.topics[0].trajectory, &ex.topics[1].trajectory);
            assert!(chain.len() > 1000, "{}", rec.display());
            assert_eq!(chain.stamps_ns, odom.stamps_ns, "{}", rec.display());
            assert_eq!(chain.positions, odom.positions, "{}", rec.display());
            assert_eq!(chain.orientations, odom.orientations, "{}", rec.display());
            assert_eq!(ex.topics[0].invalid_dropped, 0);
            checked.push((rec, chain.len()));
        }
    }
    // Five MCAP files, three ROS 1 bags, three rosbag2 folders (one of them sqlite3).
    assert_eq!(checked.len(), 11, "{checked:?}");
}

/// evo's nav2 turtlebot MCAP: `/tf` holds map→odom (921 edges) and odom→base_link (2639), and
/// `/tf_static` base_link→base_footprint among 33 static edges. The chain map→base_footprint is sampled
/// at the 2639 odom→base_link stamps; 28 of them fall outside map→odom's first..last stamp and are
/// dropped (no extrapolation), leaving 2611.
#[test]
fn nav2_turtlebot_map_to_base_footprint() {
    let Some(shared) = common::shared() else {
        return;
    };
    let rec = shared.join("evo-data/nav2_turtlebot.mcap");
    let options = ExtractOptions {
        static_lookups: vec![("base_link".into(), "base_footprint".into())],
        ..ExtractOptions::default()
    };
    let ex = extract(
        &rec,
        &[
            "/tf:map:base_footprint",
            "/tf:map:base_link",
            "/tf:base_footprint:map",
            "/tf:odom:base_link",
        ],
        &options,
    );
    let chain = &ex.topics[0];
    assert_eq!(chain.trajectory.len(), 2611);
    assert_eq!(chain.invalid_dropped, 28);
    // Edges read on the chain's pairs: 921 + 2639 + the one static edge.
    assert_eq!(chain.messages, 921 + 2639 + 1);
    assert_eq!(ex.topics[3].trajectory.len(), 2639);

    // map→base_footprint is map→base_link followed by the static base_link→base_footprint.
    let fixed = ex.static_transforms[0].pose.clone().unwrap();
    let via_link = &ex.topics[1].trajectory;
    assert_eq!(via_link.stamps_ns, chain.trajectory.stamps_ns);
    let back = &ex.topics[2].trajectory;
    for i in 0..chain.trajectory.len() {
        let expected = pose(via_link, i) * fixed;
        let got = pose(&chain.trajectory, i);
        assert!((expected.translation.vector - got.translation.vector).norm() < 1e-12);
        assert!((expected.rotation.inverse() * got.rotation).imag().norm() < 1e-12);
        // Walking the chain the other way gives the inverse.
        let id = got * pose(back, i);
        // (The imaginary part, not `angle()`: acos near 1 is only good to about 1e-8.)
        assert!(
            id.translation.vector.norm() < 1e-12 && id.rotation.imag().norm() < 1e-12,
            "{i}: {:e} {:e}",
            id.translation.vector.norm(),
            id.rotation.imag().norm()
        );
    }
}

// ---- Small recordings written here ----

fn stamp(ns: i64) -> Time {
    Time::from_ns(ns)
}

fn transform(parent: &str, child: &str, ns: i64, iso: &Isometry3<f64>) -> TransformStamped {
    let mut t = TransformStamped::default();
    t.header.frame_id = parent.into();
    t.header.stamp = stamp(ns);
    t.child_frame_id = child.into();
    let (v, q) = (iso.translation.vector, iso.rotation);
    t.transform.translation.x = v.x;
    t.transform.translation.y = v.y;
    t.transform.translation.z = v.z;
    t.transform.rotation.x = q.i;
    t.transform.rotation.y = q.j;
    t.transform.rotation.z = q.k;
    t.transform.rotation.w = q.w;
    t
}

/// Writes an MCAP with `/tf` (one message per entry of `tf`), `/tf_static` (one message) and
/// `/reference/position` PointStamped.
fn write_recording(
    path: &Path,
    tf: &[Vec<TransformStamped>],
    tf_static: &[TransformStamped],
    reference: Option<&Trajectory>,
) {
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(path).unwrap(),
    ))
    .unwrap();
    // The reader dispatches on the schema name; the text is for other tools.
    let tf_schema = w
        .add_schema(
            "tf2_msgs/msg/TFMessage",
            "ros2msg",
            b"geometry_msgs/TransformStamped[] transforms",
        )
        .unwrap();
    let point_schema = w
        .add_schema(
            "geometry_msgs/msg/PointStamped",
            "ros2msg",
            trajdrift::decode::ros2_schemas::POINT_STAMPED.as_bytes(),
        )
        .unwrap();
    let meta = BTreeMap::new();
    let tf_ch = w.add_channel(tf_schema, "/tf", "cdr", &meta).unwrap();
    let static_ch = w
        .add_channel(tf_schema, "/tf_static", "cdr", &meta)
        .unwrap();
    let point_ch = w
        .add_channel(point_schema, "/reference/position", "cdr", &meta)
        .unwrap();
    let mut seq = 0;
    let mut write = |w: &mut mcap::Writer<_>, ch: u16, ns: i64, data: Vec<u8>| {
        seq += 1;
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: ch,
                sequence: seq,
                log_time: ns as u64,
                publish_time: ns as u64,
            },
            &data,
        )
        .unwrap();
    };
    if !tf_static.is_empty() {
        let m = TFMessage {
            transforms: tf_static.to_vec(),
        };
        write(&mut w, static_ch, 1, encode_le(&m));
    }
    for transforms in tf {
        let ns = transforms[0].header.stamp.to_ns();
        let m = TFMessage {
            transforms: transforms.clone(),
        };
        write(&mut w, tf_ch, ns, encode_le(&m));
    }
    if let Some(r) = reference {
        for (t, p) in r.stamps_ns.iter().zip(&r.positions) {
            let mut m = PointStamped::default();
            m.header.stamp = stamp(*t);
            m.header.frame_id = "map".into();
            m.point.x = p.x;
            m.point.y = p.y;
            m.point.z = p.z;
            write(&mut w, point_ch, *t, encode_le(&m));
        }
    }
    w.finish().unwrap();
}

/// `n` `/tf` messages stamped 1000, 1001, … ns, each with an identity edge per (parent, child).
fn identity_edges(pairs: &[(&str, &str)], n: i64) -> Vec<Vec<TransformStamped>> {
    let id = Isometry3::identity();
    (0..n)
        .map(|i| {
            pairs
                .iter()
                .map(|(p, c)| transform(p, c, 1_000 + i, &id))
                .collect()
        })
        .collect()
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
}

/// Two trees (odom→base_link, map→gps): a chain across them is a one-line error naming what each end
/// is connected to and pointing at `trajdrift topics`.
#[test]
fn a_gap_in_the_chain_is_a_clear_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("gap.mcap");
    let tf = identity_edges(&[("odom", "base_link"), ("map", "gps")], 10);
    write_recording(&rec, &tf, &[], None);
    let o = bin()
        .arg("eval")
        .arg(&rec)
        .args([
            "--reference",
            "/tf:map:base_link",
            "--estimate",
            "/tf:odom:base_link",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("/tf:map:base_link: no TF chain from map to base_link: map is connected to [gps, map], base_link to [base_link, odom]; run `trajdrift topics"),
        "{err}"
    );
}

/// `trajdrift topics` lists the frame pairs (static and dynamic, with counts and the topic to pass)
/// and the root → leaf chains, in the table and in the JSON.
#[test]
fn topics_lists_frame_pairs_and_chains() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("tree.mcap");
    let id = Isometry3::identity();
    let tf = identity_edges(&[("map", "odom"), ("odom", "base_link")], 5);
    let fixed = [transform("/base_link", "/imu", 0, &id)];
    write_recording(&rec, &tf, &fixed, None);
    let o = bin().arg("topics").arg(&rec).output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("odom → base_link"), "{out}");
    assert!(out.contains("/tf:base_link:imu"), "{out}");
    assert!(out.contains("TF chains root → leaf: /tf:map:imu"), "{out}");
    let o = bin()
        .arg("topics")
        .arg(&rec)
        .args(["--json", "-"])
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let tf_row = v["topics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["topic"] == "/tf")
        .unwrap();
    let pairs: Vec<(String, String, bool, u64)> = tf_row["frame_pairs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p["parent"].as_str().unwrap().to_string(),
                p["child"].as_str().unwrap().to_string(),
                p["is_static"].as_bool().unwrap(),
                p["count"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        pairs,
        vec![
            ("map".into(), "odom".into(), false, 5),
            ("odom".into(), "base_link".into(), false, 5)
        ]
    );
    assert_eq!(tf_row["tf_chains"], serde_json::json!(["/tf:map:imu"]));
    let static_row = v["topics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["topic"] == "/tf_static")
        .unwrap();
    assert_eq!(static_row["frame_pairs"][0]["chain"], "/tf:base_link:imu");
    assert_eq!(static_row["frame_pairs"][0]["is_static"], true);
}

/// A simulated mission written with the estimate as `/tf` odom→base_link (base_link = the estimate
/// sensor) and the GNSS antenna as a `/tf_static` frame: `--reference-lever tf-static:gnss` (BODY is
/// the chain's CHILD, base_link) must give exactly the report of `--reference-lever X,Y,Z` with the
/// antenna's numbers.
fn lever_recording(dir: &Path) -> (PathBuf, [f64; 3]) {
    let mission = simulate(&MissionConfig::default(), &default_route());
    let c = &mission.config;
    let lever = [
        c.ref_lever_m[0] - c.est_lever_m[0],
        c.ref_lever_m[1] - c.est_lever_m[1],
        c.ref_lever_m[2] - c.est_lever_m[2],
    ];
    let est = &mission.estimate;
    let tf: Vec<Vec<TransformStamped>> = (0..est.len())
        .map(|i| {
            vec![transform(
                "odom",
                "base_link",
                est.stamps_ns[i],
                &pose(est, i),
            )]
        })
        .collect();
    // The antenna hangs off a mount frame, so the lever is composed from two static edges.
    let mount = Isometry3::from_parts(
        Translation3::new(0.1, 0.0, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
    );
    let antenna_in_mount = (mount.inverse() * Point3::from(lever)).coords;
    let fixed = [
        transform("base_link", "mount", 0, &mount),
        transform(
            "mount",
            "gnss",
            0,
            &Isometry3::from_parts(
                Translation3::from(antenna_in_mount),
                UnitQuaternion::identity(),
            ),
        ),
    ];
    let rec = dir.join("lever.mcap");
    write_recording(&rec, &tf, &fixed, Some(&mission.reference));
    (rec, lever)
}

fn lever_config(rec: &Path, lever: LeverSpec) -> EvalConfig {
    let mut c = EvalConfig::new(
        Some(rec.to_path_buf()),
        NamedInput::topic("/reference/position"),
        vec![NamedInput::topic("/tf:odom:base_link")],
    );
    c.reference_lever = Some(lever);
    c.params.time_offset = Some(0.2);
    c
}

#[test]
fn tf_static_lever_equals_the_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, lever) = lever_recording(dir.path());
    let by_frame = evaluate(&lever_config(
        &rec,
        LeverSpec::TfStatic {
            body: None,
            frame: "gnss".into(),
        },
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    let x = by_frame.estimates[0].extrinsics.clone().unwrap();
    for k in 0..3 {
        assert!(
            (x.reference_lever_m[k] - lever[k]).abs() < 1e-12,
            "{x:?} {lever:?}"
        );
    }
    let resolved = LeverSpec::Offset(x.reference_lever_m);
    let by_numbers = evaluate(&lever_config(&rec, resolved)).unwrap();
    assert_eq!(
        serde_json::to_value(&by_frame.estimates).unwrap(),
        serde_json::to_value(&by_numbers.estimates).unwrap()
    );
    assert_eq!(by_frame.estimates[0].type_name, "tf2_msgs/msg/TFMessage");

    // Errors: an unknown frame, a frame behind a moving edge, and no body frame to measure in.
    let err = |spec: LeverSpec, estimate: &str| {
        let mut c = lever_config(&rec, spec);
        c.estimates = vec![NamedInput::topic(estimate)];
        evaluate(&c).unwrap_err().to_string()
    };
    let e = err(
        LeverSpec::parse("--reference-lever", "tf-static:radar").unwrap(),
        "/tf:odom:base_link",
    );
    assert!(
        e.contains(
            "--reference-lever tf-static:radar: frame `radar` is in no /tf or /tf_static edge"
        ),
        "{e}"
    );
    let e = err(
        LeverSpec::parse("--reference-lever", "tf-static:odom").unwrap(),
        "/tf:odom:base_link",
    );
    assert!(e.contains("has a /tf (moving) edge"), "{e}");
    let mut c = lever_config(
        &rec,
        LeverSpec::parse("--reference-lever", "tf-static:gnss").unwrap(),
    );
    c.estimates = vec![NamedInput::topic("est=/reference/position")];
    let e = evaluate(&c).unwrap_err().to_string();
    assert!(e.contains("write tf-static:BODY:gnss"), "{e}");

    // The same from the command line; a malformed spec is a usage error (exit 2).
    let eval = |lever: &str| {
        bin()
            .arg("eval")
            .arg(&rec)
            .args([
                "--reference",
                "/reference/position",
                "--estimate",
                "/tf:odom:base_link",
                "--time-offset",
                "0.2",
                "--json",
                "-",
                "--reference-lever",
                lever,
            ])
            .output()
            .unwrap()
    };
    let o = eval("tf-static:base_link:gnss");
    assert!(
        matches!(o.status.code(), Some(0) | Some(3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        serde_json::to_value(x.reference_lever_m).unwrap(),
        v["estimates"][0]["extrinsics"]["reference_lever_m"]
    );
    let o = eval("tf-static:");
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("tf-static: takes a frame, or BODY:FRAME"));
}

/// An aligned TF-chain estimate has no message of its own to patch: the annotated copy writes it as
/// PoseStamped from its samples, one message per sample.
#[test]
fn annotated_chain_estimates_are_written_as_poses() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let rec = common::mission(&shared, "lever_arm").join("mission.mcap");
    let out = dir.path().join("out.mcap");
    let json = dir.path().join("out.json");
    let o = bin()
        .arg("eval")
        .arg(&rec)
        .args([
            "--reference",
            "/reference/position",
            "--estimate",
            "/tf:odom:base_link",
            "--quiet",
            "--annotate",
        ])
        .arg(&out)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        matches!(o.status.code(), Some(0) | Some(3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let samples = report["estimates"][0]["samples"].as_u64().unwrap();
    let buf = std::fs::read(&out).unwrap();
    let summary = mcap::Summary::read(&buf).unwrap().unwrap();
    let (id, channel) = summary
        .channels
        .iter()
        .find(|(_, c)| c.topic == "/trajdrift/tf/odom/base_link/aligned")
        .expect("aligned channel");
    let schema = channel.schema.as_ref().unwrap();
    assert_eq!(schema.name, "geometry_msgs/msg/PoseStamped");
    let count = summary.stats.as_ref().unwrap().channel_message_counts[id];
    assert_eq!(count, samples);
}

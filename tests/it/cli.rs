//! The command line as a user meets it: exit codes, one-line errors, negative numbers as values, JSON
//! output. Recordings are written by the project's own simulator into temporary folders.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use trajdrift::simulate::writer::write_mcap;
use trajdrift::simulate::{default_route, simulate, MissionConfig};
use trajdrift::sources::tum::write_tum;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run trajdrift")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A simulated mission with a small unrelated bulk channel, as MCAP and TUM files.
fn recording(dir: &Path) -> PathBuf {
    let mission = simulate(&MissionConfig::default(), &default_route());
    let path = dir.join("mission.mcap");
    write_mcap(
        std::io::BufWriter::new(std::fs::File::create(&path).unwrap()),
        &mission,
        256,
    )
    .unwrap();
    write_tum(
        std::fs::File::create(dir.join("reference.tum")).unwrap(),
        &mission.reference,
    )
    .unwrap();
    write_tum(
        std::fs::File::create(dir.join("estimate.tum")).unwrap(),
        &mission.estimate,
    )
    .unwrap();
    path
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn eval_prints_a_table_and_writes_json() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let json = dir.path().join("out.json");
    let o = run(&[
        "eval",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "lio=/estimate/odom",
        "--platform",
        "wheeled",
        "--window",
        "1,5,10",
        "--offset-method",
        "speed",
        "--json",
        s(&json),
    ]);
    assert!(
        o.status.code() == Some(0) || o.status.code() == Some(3),
        "{}",
        stderr(&o)
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("estimate lio"), "{out}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["schema_version"], 1);
    assert_eq!(
        report["estimates"][0]["drift_error"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    let dt = report["estimates"][0]["time_offset"]["offset_s"]
        .as_f64()
        .unwrap();
    assert!((dt - 0.2).abs() < 0.03, "speed offset {dt}");
    assert_eq!(report["parameters"]["path_eps_m"], 0.3);
}

// A usage error is one line, as every error: clap's message, what it lists or suggests, and the
// command whose --help says more.
#[test]
fn usage_errors_are_one_line() {
    for args in [
        &["eval", "--estimate-file", "e.tum"][..],
        &["eval", "--bogus"],
        &["completions", "nope"],
        &["eval", "--origin", "1,2"],
        &["nope"],
    ] {
        let o = run(args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{args:?}: {e}");
        assert!(
            e.starts_with("error: ") && e.contains(" --help`"),
            "{args:?}: {e}"
        );
    }
    let e = stderr(&run(&["eval", "--bogus"]));
    assert!(e.contains("see `trajdrift eval --help`"), "{e}");
}

#[test]
fn negative_numbers_are_values() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let o = run(&[
        "eval",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--time-offset",
        "-0.35",
        "--origin",
        "-33.9,151.2,40",
        "--t-start",
        "-5",
        "--json",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["estimates"][0]["time_offset"]["applied_s"], -0.35);
    assert_eq!(report["parameters"]["origin"][0], -33.9);
}

#[test]
fn missing_topic_lists_the_topics_present() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let o = run(&[
        "eval",
        s(&rec),
        "--reference",
        "/nope",
        "--estimate",
        "/estimate/odom",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("/nope") && e.contains("/reference/position") && e.contains("mission.mcap"),
        "{e}"
    );
    assert_eq!(e.trim().lines().count(), 1, "{e}");
}

#[test]
fn unsupported_type_lists_the_supported_ones() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let o = run(&[
        "eval",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "/camera/raw",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("sensor_msgs/msg/Image") && e.contains("nav_msgs/msg/Odometry"),
        "{e}"
    );
}

#[test]
fn too_few_samples() {
    let dir = tempfile::tempdir().unwrap();
    recording(dir.path());
    let short = dir.path().join("short.tum");
    std::fs::write(
        &short,
        "1718460000.0 0 0 0 0 0 0 1\n1718460001.0 1 0 0 0 0 0 1\n",
    )
    .unwrap();
    let o = run(&[
        "eval",
        "--reference-file",
        s(&dir.path().join("reference.tum")),
        "--estimate-file",
        s(&short),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("only 2 usable samples"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn no_time_overlap() {
    let dir = tempfile::tempdir().unwrap();
    let mission = simulate(&MissionConfig::default(), &default_route());
    let late = mission.estimate.shifted(3_600_000_000_000);
    write_tum(
        std::fs::File::create(dir.path().join("r.tum")).unwrap(),
        &mission.reference,
    )
    .unwrap();
    write_tum(
        std::fs::File::create(dir.path().join("e.tum")).unwrap(),
        &late,
    )
    .unwrap();
    for extra in [&[][..], &["--time-offset", "0"][..]] {
        let mut args = vec!["eval", "--reference-file"];
        let (r, e) = (dir.path().join("r.tum"), dir.path().join("e.tum"));
        args.extend([s(&r), "--estimate-file", s(&e)]);
        args.extend(extra);
        let o = run(&args);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains("do not overlap"), "{}", stderr(&o));
    }
}

#[test]
fn not_an_mcap_file() {
    let dir = tempfile::tempdir().unwrap();
    let txt = dir.path().join("notes.mcap");
    std::fs::write(&txt, "this is not a recording\n").unwrap();
    let o = run(&["eval", s(&txt), "--reference", "/a", "--estimate", "/b"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("notes.mcap") && e.contains("not an MCAP"), "{e}");
    let o = run(&["topics", s(&txt)]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn truncated_recording_is_read_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let bytes = std::fs::read(&rec).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 7 / 10]).unwrap();
    let o = run(&[
        "eval",
        s(&cut),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--time-offset",
        "0.2",
        "--json",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("truncated"), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let n = report["reference"]["samples"].as_u64().unwrap();
    assert!(n > 100 && n < 1500, "{n}");
    assert_eq!(
        std::fs::read(&rec).unwrap(),
        bytes,
        "the input is never modified"
    );
}

#[test]
fn topics_lists_channels() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(dir.path());
    let o = run(&["topics", s(&rec)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("/reference/position") && out.contains("/camera/raw"),
        "{out}"
    );
    let o = run(&["topics", s(&rec), "--json", "-"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["presets"], serde_json::json!([]));
    let odom = v["topics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["topic"] == "/estimate/odom")
        .unwrap();
    assert_eq!(odom["readable"], true);
    assert!(odom["message_count"].as_u64().unwrap() > 2000);
}

#[test]
fn usage_errors_exit_2() {
    assert_eq!(run(&["eval", "--estimate", "/x"]).status.code(), Some(2));
    assert_eq!(run(&["frobnicate"]).status.code(), Some(2));
}

#[test]
fn weak_offset_exits_3_and_still_writes_json() {
    // A straight line at constant speed: neither curvature nor speed can tell the offset.
    let dir = tempfile::tempdir().unwrap();
    let route = [trajdrift::simulate::motion::Segment {
        duration_s: 60.0,
        speed_mps: 1.5,
        curvature: 0.0,
    }];
    let cfg = MissionConfig {
        ref_noise_m: 0.0,
        est_noise_m: 0.0,
        ..MissionConfig::default()
    };
    let mission = simulate(&cfg, &route);
    let mut reference = mission.reference.clone();
    reference.crop(Some(cfg.start_time_ns + 5_000_000_000), None);
    write_tum(
        std::fs::File::create(dir.path().join("r.tum")).unwrap(),
        &reference,
    )
    .unwrap();
    write_tum(
        std::fs::File::create(dir.path().join("e.tum")).unwrap(),
        &mission.estimate,
    )
    .unwrap();
    let json = dir.path().join("weak.json");
    let (r, e) = (dir.path().join("r.tum"), dir.path().join("e.tum"));
    let o = run(&[
        "eval",
        "--reference-file",
        s(&r),
        "--estimate-file",
        s(&e),
        "--json",
        s(&json),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["estimates"][0]["time_offset"]["status"], "weak");
    assert_eq!(report["estimates"][0]["time_offset"]["applied_s"], 0.0);
}

/// Runs `args`, and checks the failure a user sees: a non-zero exit without a panic, and one line on
/// stderr naming `file` and containing `what`.
fn one_line_failure(args: &[&str], file: &str, what: &str) {
    let o = run(args);
    let e = stderr(&o);
    assert!(
        matches!(o.status.code(), Some(1 | 2)),
        "{args:?}: {:?} {e}",
        o.status
    );
    assert!(!e.contains("panicked"), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{args:?}: {e}");
    assert!(
        e.contains(file) && e.contains(what),
        "{args:?}: {file}, {what}: {e}"
    );
}

#[test]
fn bad_recordings_and_mappings_are_one_line_errors() {
    use trajdrift::decode::ros1;
    use trajdrift::decode::ros2_msgs::{Header, Odometry, Time};
    use trajdrift::sources::bag::writer::{BagCompression, BagWriter};
    let dir = tempfile::tempdir().unwrap();

    // A ROS 1 bag whose chunks use a compression trajdrift does not read.
    let bag = dir.path().join("zstd.bag");
    let f = std::io::BufWriter::new(std::fs::File::create(&bag).unwrap());
    let mut w = BagWriter::new(f, BagCompression::Other("zstd".into()), 4096).unwrap();
    let c = w.add_connection("/estimate/odom", "nav_msgs/Odometry");
    for i in 0..50u32 {
        let ns = 1_700_000_000_000_000_000 + i as i64 * 10_000_000;
        let o = Odometry {
            header: Header {
                stamp: Time::from_ns(ns),
                frame_id: "odom".into(),
            },
            ..Default::default()
        };
        w.write(c, ns as u64, &ros1::encode_odometry(i, &o))
            .unwrap();
    }
    w.finish().unwrap();
    let eval = |rec: &str| {
        vec![
            "eval".to_string(),
            rec.to_string(),
            "--reference".into(),
            "/estimate/odom".into(),
            "--estimate".into(),
            "/estimate/odom".into(),
        ]
    };
    let args = eval(s(&bag));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    one_line_failure(&args, "zstd.bag", "compression `zstd`");
    one_line_failure(
        &["export", s(&bag), "--topic", "/estimate/odom", "-"],
        "zstd.bag",
        "compression `zstd`",
    );

    // A rosbag2 folder whose metadata names a file that is not there.
    let folder = dir.path().join("run_rosbag2");
    std::fs::create_dir(&folder).unwrap();
    std::fs::write(
        folder.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths: [run_0.mcap]\n",
    )
    .unwrap();
    let args = eval(s(&folder));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    one_line_failure(&args, "run_rosbag2", "run_0.mcap, which is missing");
    one_line_failure(&["topics", s(&folder)], "run_rosbag2", "which is missing");

    // A CSV mapping naming a column the file does not have.
    let csv = dir.path().join("odom.csv");
    std::fs::write(&csv, "stamp,px,py,pz\n1,0,0,0\n2,1,0,0\n3,2,0,0\n").unwrap();
    let mapping = "t=stamp:us,x=px,y=py,z=height";
    one_line_failure(
        &[
            "eval",
            "--reference-file",
            s(&csv),
            "--estimate-file",
            s(&csv),
            "--csv",
            mapping,
        ],
        "odom.csv",
        "`height`",
    );
    one_line_failure(
        &["export", s(&csv), "--csv", mapping, "-"],
        "odom.csv",
        "`height`",
    );
}

/// `simulate --clock-step AT:OFFSET` steps the estimate's clock; `eval` finds a piecewise model with
/// the truth's two offsets and its change time. A malformed step is a usage error.
#[test]
fn simulated_clock_step_is_found_piecewise() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, json) = (dir.path().join("step.mcap"), dir.path().join("step.json"));
    let o = run(&[
        "simulate",
        s(&rec),
        "--laps",
        "3",
        "--clock-step",
        "300:-0.1",
        "--truth",
        s(&dir.path().join("truth.json")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(&[
        "eval",
        s(&rec),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--quiet",
        "--json",
        s(&json),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("clock_step_suspected"),
        "{}",
        stderr(&o)
    );
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let t = &report["estimates"][0]["time_offset"];
    assert_eq!(t["model"], "piecewise");
    let seg = t["segments"].as_array().unwrap();
    assert_eq!(seg.len(), 2);
    let (first, second) = (
        seg[0]["offset_s"].as_f64().unwrap(),
        seg[1]["offset_s"].as_f64().unwrap(),
    );
    assert!(
        (first - 0.2).abs() < 0.01 && (second + 0.1).abs() < 0.01,
        "{seg:?}"
    );
    // The change on the reference clock within a few seconds of the truth's (its stamps are true time).
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("truth.json")).unwrap()).unwrap();
    assert_eq!(truth["config"]["clock_step"]["at_s"], 300.0);
    let start = truth["config"]["start_time_ns"].as_i64().unwrap() as f64 * 1e-9;
    let change = seg[0]["t_end"].as_f64().unwrap() - start;
    assert!((change - 300.0).abs() < 5.0, "change at {change} s");
    let o = run(&[
        "simulate",
        s(&dir.path().join("x.mcap")),
        "--clock-step",
        "3:oops",
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// `simulate --duration S --est-rate HZ` (the throughput bench's recording, scaled down): the route repeated and
/// cut to S seconds, the estimate at HZ; `--duration` and `--laps` exclude each other.
#[test]
fn simulate_takes_a_duration_and_an_estimate_rate() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("long.mcap");
    let o = run(&["simulate", s(&rec), "--duration", "400", "--est-rate", "50"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("(400 s, 4001 reference and 20001 estimate samples)"),
        "{}",
        stderr(&o)
    );
    let o = run(&[
        "simulate",
        s(&rec),
        "--force",
        "--duration",
        "10",
        "--laps",
        "2",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&["simulate", s(&rec), "--force", "--est-rate", "0"]);
    assert_eq!(o.status.code(), Some(2));
}

//! The output policy at the process boundary: an output that is an input, lies in an input folder, is
//! another output of the same command or a name another result of the run takes is refused (exit 2)
//! before any work, and nothing is written; devices, FIFOs and symlinks to them are written through;
//! regular files are replaced whole, with no temporary file left behind; I/O errors name their cause.
//! Every input's bytes are unchanged after every case.

use std::path::Path;

use crate::hostile_support::EstimateMsg;

use crate::robust_support::{
    eval_args, expect_code, mkfifo, run, s, stderr, stdout, Fixture, Snapshot,
};

/// Runs `args`, expects a one-line refusal (exit 2) containing `says`, and no new file in `dir`.
#[track_caller]
fn refused(f: &Fixture, args: &[&str], says: &str) {
    refused_by(f, crate::robust_support::bin(), args, says);
}

/// [`refused`], with `cmd` (a working folder of its own) running `args`.
#[track_caller]
fn refused_by(f: &Fixture, mut cmd: std::process::Command, args: &[&str], says: &str) {
    let before = f.names("");
    let o = cmd.args(args).output().expect("run trajdrift");
    let e = stderr(&o);
    expect_code(&o, &[2], &format!("{args:?}"));
    assert!(e.contains(says), "{args:?}: {e}");
    assert_eq!(e.lines().count(), 1, "{args:?}: {e}");
    assert_eq!(f.names(""), before, "{args:?} wrote something");
}

#[test]
fn outputs_over_inputs_or_other_outputs_are_refused_before_any_work() {
    let f = Fixture::new();
    // A rosbag2 folder (its metadata.yaml and database), a mission folder, a sweep output folder
    // holding an input.
    let bag = f.p("bag2");
    std::fs::create_dir(&bag).unwrap();
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information: {}\n",
    )
    .unwrap();
    std::fs::write(bag.join("bag2.db3"), "not read").unwrap();
    let mission = f.p("mission");
    std::fs::create_dir(&mission).unwrap();
    std::fs::copy(f.p("in.mcap"), mission.join("a.mcap")).unwrap();
    let sweep = f.p("sweep");
    std::fs::create_dir(&sweep).unwrap();
    std::fs::copy(f.p("est.tum"), sweep.join("sweep.csv")).unwrap();
    let snap = Snapshot::of(&[f.dir.path()]);
    let (rec, r, e) = (f.p("in.mcap"), f.p("ref.tum"), f.p("est.tum"));
    let text = |extra: &[&'static str]| -> Vec<String> {
        let mut v: Vec<String> = vec![
            "eval".into(),
            "--reference-file".into(),
            s(&r).into(),
            "--estimate-file".into(),
            s(&e).into(),
            "-q".into(),
        ];
        v.extend(extra.iter().map(|x| x.to_string()));
        v
    };
    let owned = |v: Vec<String>| v;
    let meta = bag.join("metadata.yaml");
    let x = f.p("x.out");
    let cases: Vec<(Vec<String>, &str)> = vec![
        // The issue's examples.
        (
            owned([text(&[]), vec!["--html".into(), s(&r).into()]].concat()),
            "writing it would destroy the input",
        ),
        (
            owned(
                [
                    vec!["eval".into(), s(&bag).into()],
                    vec![
                        "--reference".into(),
                        "/r".into(),
                        "--estimate".into(),
                        "/e".into(),
                    ],
                    vec!["--html".into(), s(&meta).into()],
                ]
                .concat(),
            ),
            "a file inside the input folder",
        ),
        (
            owned(vec![
                "topics".into(),
                s(&rec).into(),
                "--json".into(),
                s(&rec).into(),
            ]),
            "writing it would destroy the input",
        ),
        (
            owned(
                [
                    vec!["sweep".into(), "--param".into(), "window".into()],
                    vec![
                        "--values".into(),
                        "5,10".into(),
                        "--out".into(),
                        s(&sweep).into(),
                    ],
                    vec!["--reference-file".into(), s(&r).into()],
                    vec!["--estimate-file".into(), s(&sweep.join("sweep.csv")).into()],
                ]
                .concat(),
            ),
            "writing it would destroy the input",
        ),
        (
            owned(vec![
                "simulate".into(),
                s(&f.p("s.mcap")).into(),
                "--truth".into(),
                s(&f.p("s.mcap")).into(),
            ]),
            "writes the same file",
        ),
        (
            eval_args(s(&rec), &["--json", s(&x), "--annotate", s(&x)])
                .into_iter()
                .map(String::from)
                .collect(),
            "--json writes the same file",
        ),
        (
            eval_args(s(&mission), &["--plot", s(&mission.join("figures"))])
                .into_iter()
                .map(String::from)
                .collect(),
            "a file inside the input folder",
        ),
        // More of the same kind.
        (
            owned(
                [
                    text(&[]),
                    vec![
                        "--json".into(),
                        "-".into(),
                        "--html".into(),
                        "/dev/stdout".into(),
                    ],
                ]
                .concat(),
            ),
            "writes the same file",
        ),
        (
            owned(
                [
                    text(&[]),
                    vec!["--json".into(), s(&f.p("new/../x.json")).into()],
                    vec!["--html".into(), s(&f.p("./x.json")).into()],
                ]
                .concat(),
            ),
            "writes the same file",
        ),
        (
            owned([text(&[]), vec!["--export-aligned".into(), s(&e).into()]].concat()),
            "writing it would destroy the input",
        ),
        (
            owned(vec![
                "ape".into(),
                "tum".into(),
                s(&r).into(),
                s(&e).into(),
                "--json".into(),
                s(&e).into(),
            ]),
            "writing it would destroy the input",
        ),
        (
            owned(vec![
                "offset".into(),
                "tum".into(),
                s(&r).into(),
                s(&e).into(),
                "--json".into(),
                s(&r).into(),
            ]),
            "writing it would destroy the input",
        ),
        (
            owned(vec![
                "export".into(),
                s(&mission).into(),
                "--topic".into(),
                "/estimate/odom".into(),
                s(&mission.join("a.tum")).into(),
            ]),
            "a file inside the input folder",
        ),
        (
            owned(vec![
                "topics".into(),
                s(&bag).into(),
                "--json".into(),
                s(&bag.join("bag2.db3")).into(),
            ]),
            "a file inside the input folder",
        ),
        (
            owned(vec![
                "simulate".into(),
                s(&f.p("gt")).into(),
                "--grandtour".into(),
                "--truth".into(),
                s(&f.p("gt/2024-06-15-14-00-00_dlio.bag")).into(),
            ]),
            "writes the same file",
        ),
    ];
    for (args, says) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused(&f, &args, says);
    }
    snap.assert_unchanged();
}

#[test]
fn names_that_map_to_one_file_or_channel_are_refused() {
    let f = Fixture::new();
    let snap = Snapshot::of(&[f.dir.path()]);
    let rec = f.p("in.mcap");
    let two = |a: &str, b: &str, extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = vec![
            "eval".into(),
            s(&rec).into(),
            "--reference".into(),
            "/reference/position".into(),
            "--estimate".into(),
            format!("{a}=/estimate/odom"),
            "--estimate".into(),
            format!("{b}=/estimate/pose"),
            "--time-offset".into(),
            "0.2".into(),
            "-q".into(),
        ];
        v.extend(extra.iter().map(|x| x.to_string()));
        v
    };
    let plot = f.p("figs");
    let aligned = f.p("al.tum");
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            two("a.b", "a_b", &["--plot", s(&plot)]),
            "estimates `a.b` and `a_b` both map to the file name `a_b`",
        ),
        (
            two("LIO", "lio", &["--export-aligned", s(&aligned)]),
            "both map to the file name",
        ),
        (
            two("reference", "odom", &["--annotate", s(&f.p("ann.mcap"))]),
            "estimate `reference` would write the channel /trajdrift/reference/curvature",
        ),
    ];
    for (args, says) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused(&f, &args, says);
    }
    // Topics that differ only by `/` and `_` name their estimates apart by default.
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("odom.bag");
    crate::hostile_support::BagShape {
        z_m: 0.0,
        chunk_bytes: 4096,
        estimates: &[
            ("/odom/filtered", EstimateMsg::Odometry),
            ("/odom_filtered", EstimateMsg::Odometry),
        ],
        ..Default::default()
    }
    .write(&bag);
    let o = run(&[
        "eval",
        s(&bag),
        "--reference",
        "/reference/position",
        "--estimate",
        "/odom/filtered",
        "--estimate",
        "/odom_filtered",
        "--plot",
        s(&dir.path().join("figs")),
        "-q",
    ]);
    expect_code(&o, &[2], "odom/filtered vs odom_filtered");
    assert!(
        stderr(&o).contains("`odom/filtered` and `odom_filtered`"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.path().join("figs").exists());
    snap.assert_unchanged();
}

#[test]
fn devices_fifos_and_symlinks_are_written_through() {
    let f = Fixture::new();
    let snap = Snapshot::of(&[&f.p("in.mcap")]);
    let rec = f.p("in.mcap");
    // /dev/stdout prints the report (and nothing else on stdout).
    let o = run(&eval_args(s(&rec), &["--json", "/dev/stdout"]));
    expect_code(&o, &[0, 3], "--json /dev/stdout");
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON on stdout");
    assert_eq!(v["estimates"][0]["name"], "estimate/odom");
    // /dev/null stays a device (as root, a rename would replace it). On a shared machine another
    // program may already have replaced it: then there is nothing to show.
    let device = |p: &str| std::fs::metadata(p).is_ok_and(|m| !m.is_file());
    let was_device = device("/dev/null");
    let o = run(&eval_args(s(&rec), &["--json", "/dev/null"]));
    expect_code(&o, &[0, 3], "--json /dev/null");
    if was_device {
        assert!(device("/dev/null"), "/dev/null was replaced");
    } else {
        eprintln!("/dev/null was not a device before the test: not checked");
    }
    // A FIFO, and a symlink to one, get the data; nothing replaces them.
    let fifo = f.p("out.fifo");
    mkfifo(&fifo);
    let link = f.p("link.json");
    std::os::unix::fs::symlink(&fifo, &link).unwrap();
    for target in [&fifo, &link] {
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).unwrap())
        };
        let o = run(&eval_args(s(&rec), &["--json", s(target)]));
        expect_code(&o, &[0, 3], "--json FIFO");
        let got = reader.join().unwrap();
        let v: serde_json::Value = serde_json::from_slice(&got).expect("JSON through the FIFO");
        assert_eq!(v["schema_version"], 1);
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    }
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    // A symlink to a regular file keeps pointing at it; the file gets the new content.
    let target = f.p("target.json");
    std::fs::write(&target, "old").unwrap();
    let to_file = f.p("to-file.json");
    std::os::unix::fs::symlink("target.json", &to_file).unwrap();
    let o = run(&eval_args(s(&rec), &["--json", s(&to_file)]));
    expect_code(&o, &[0, 3], "--json symlink");
    assert!(std::fs::symlink_metadata(&to_file)
        .unwrap()
        .file_type()
        .is_symlink());
    let _: serde_json::Value = serde_json::from_slice(&std::fs::read(&target).unwrap()).unwrap();
    assert!(!f.names("").iter().any(|n| n.ends_with(".tmp")));
    snap.assert_unchanged();
}

#[test]
fn temporary_files_are_removed_and_stale_ones_recognised_by_their_lock() {
    let f = Fixture::new();
    let rec = f.p("in.mcap");
    let out = f.p("out.json");
    // A killed writer's file (unlocked), and a live writer's (locked by this test) of the same name.
    let stale = f.p(".out.json.1234abcd.tmp");
    std::fs::write(&stale, "half a report").unwrap();
    let live = f.p(".out.json.feedbeef.tmp");
    std::fs::write(&live, "being written").unwrap();
    let held = std::fs::File::open(&live).unwrap();
    // SAFETY: flock on a descriptor we own.
    assert_eq!(
        unsafe { libc::flock(std::os::unix::io::AsRawFd::as_raw_fd(&held), libc::LOCK_EX) },
        0
    );
    let o = run(&eval_args(s(&rec), &["--json", s(&out)]));
    expect_code(&o, &[0, 3], "eval --json");
    assert!(!stale.exists(), "a stale temporary file is left");
    assert!(live.exists(), "a live writer's temporary file was removed");
    drop(held);
    // A failed rename (the target is a non-empty folder) leaves no temporary file and says why.
    let taken = f.p("taken");
    std::fs::create_dir(&taken).unwrap();
    std::fs::write(taken.join("x"), "x").unwrap();
    let o = run(&eval_args(s(&rec), &["--json", s(&taken)]));
    expect_code(&o, &[1], "--json onto a folder");
    assert!(stderr(&o).contains("is a folder"), "{}", stderr(&o));
    let o = run(&[
        "export",
        s(&rec),
        "--topic",
        "/estimate/odom",
        s(&f.p("taken/x/y.tum")),
    ]);
    expect_code(&o, &[1], "export under a file");
    let left: Vec<String> = f
        .names("")
        .into_iter()
        .chain(f.names("taken"))
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert_eq!(left, [".out.json.feedbeef.tmp"], "{left:?}");
}

#[test]
fn io_errors_name_their_cause_and_what_to_do() {
    let f = Fixture::new();
    let rec = f.p("in.mcap");
    let long = f.p(&"n".repeat(300));
    let under_file = f.p("ref.tum/x.json");
    let cases: [(&Path, &str); 3] = [
        (&long, "longer than the file system allows"),
        (&under_file, "a part of the path is a file, not a folder"),
        (Path::new("/dev/full"), "the disk is full"),
    ];
    for (out, says) in cases {
        let o = run(&eval_args(s(&rec), &["--json", s(out)]));
        let e = stderr(&o);
        expect_code(&o, &[1], says);
        assert!(e.contains(says), "{says}: {e}");
        assert!(!e.contains("the disk is healthy"), "{says}: {e}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }
    // Read-only and busy are unit-tested on the error codes (`error::tests`): no test machine can
    // be counted on to have a read-only file system or a busy file to write to.
}

/// Runs `args` in the fixture's folder (outputs named by the data, such as `traj --save_as_tum`'s,
/// go there), expects a one-line refusal (exit 2) containing `says`, and no new file in it.
#[track_caller]
fn refused_here(f: &Fixture, args: &[&str], says: &str) {
    let mut cmd = crate::robust_support::bin();
    cmd.current_dir(f.dir.path());
    refused_by(f, cmd, args, says);
}

#[test]
fn every_file_a_command_reads_is_an_input() {
    let f = Fixture::new();
    std::fs::write(f.p("conf.json"), "{\"align\": true}\n").unwrap();
    std::fs::write(
        f.p("tf.json"),
        "{\"x\": 0, \"y\": 0, \"z\": 0, \"qx\": 0, \"qy\": 0, \"qz\": 0, \"qw\": 1}\n",
    )
    .unwrap();
    let o = run(&[
        "audit",
        s(&f.p("in.mcap")),
        "--json",
        s(&f.p("a.json")),
        "-q",
    ]);
    expect_code(&o, &[0, 3], "audit");
    let snap = Snapshot::of(&[f.dir.path()]);
    let (r, e) = (f.p("ref.tum"), f.p("est.tum"));
    let (conf, tf, audit) = (f.p("conf.json"), f.p("tf.json"), f.p("a.json"));
    let (r, e, conf, tf, audit, rec) = (s(&r), s(&e), s(&conf), s(&tf), s(&audit), f.p("in.mcap"));
    let says = "writing it would destroy the input";
    for flag in ["--json", "--logfile"] {
        refused(&f, &["ape", "tum", r, e, "-c", conf, flag, conf], says);
    }
    refused(
        &f,
        &["rpe", "tum", r, e, "--config", conf, "--logfile", conf],
        says,
    );
    for flag in ["--save_table", "--logfile"] {
        refused(
            &f,
            &["traj", "tum", e, "--transform_left", tf, flag, tf],
            says,
        );
        refused(
            &f,
            &["traj", "tum", e, "--transform_right", tf, flag, tf],
            says,
        );
        refused(&f, &["traj", "tum", e, "-c", conf, flag, conf], says);
    }
    refused(
        &f,
        &[
            "restamp",
            s(&rec),
            "--audit",
            audit,
            "--out",
            audit,
            "--force",
        ],
        says,
    );
    snap.assert_unchanged();
}

#[cfg(unix)]
#[test]
fn files_read_through_a_folder_are_inputs_wherever_they_are() {
    let f = Fixture::new();
    std::fs::copy(f.p("in.mcap"), f.p("victim.mcap")).unwrap();
    // A mission folder holding a symlink out of it.
    std::fs::create_dir(f.p("ml")).unwrap();
    std::os::unix::fs::symlink("../victim.mcap", f.p("ml/a.mcap")).unwrap();
    // A rosbag2 folder whose metadata.yaml names a file outside it.
    std::fs::create_dir(f.p("rb")).unwrap();
    std::fs::write(
        f.p("rb/metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths:\n  - ../victim.mcap\n",
    )
    .unwrap();
    let snap = Snapshot::of(&[f.dir.path()]);
    let victim = f.p("victim.mcap");
    for folder in ["ml", "rb", "rb/metadata.yaml"] {
        let rec = f.p(folder);
        refused(
            &f,
            &eval_args(s(&rec), &["--json", s(&victim)]),
            "writing it would destroy the input",
        );
        refused(
            &f,
            &["topics", s(&rec), "--json", s(&victim)],
            "writing it would destroy the input",
        );
    }
    snap.assert_unchanged();
}

#[test]
fn trajectories_of_one_name_are_not_converted_into_one_file() {
    let f = Fixture::new();
    for d in ["d1", "d2"] {
        std::fs::create_dir(f.p(d)).unwrap();
        std::fs::copy(f.p("est.tum"), f.p(&format!("{d}/est.tum"))).unwrap();
    }
    let snap = Snapshot::of(&[f.dir.path()]);
    let two = ["traj", "tum", "d1/est.tum", "d2/est.tum"];
    for (extra, says) in [
        (&["--save_as_tum"][..], "would both be written to est.tum"),
        (
            &["--save_as_kitti"][..],
            "would both be written to est.kitti",
        ),
        (
            &["--save_as_mcap", "t.mcap"][..],
            "would both be written on the topic /est of t.mcap",
        ),
    ] {
        refused_here(&f, &[&two[..], extra].concat(), says);
    }
    snap.assert_unchanged();
}

#[test]
fn simulate_replaces_an_existing_truth_only_with_force() {
    let f = Fixture::new();
    std::fs::write(f.p("truth.json"), "old").unwrap();
    let (out, truth) = (f.p("s.mcap"), f.p("truth.json"));
    let args = ["simulate", s(&out), "--truth", s(&truth), "--duration", "5"];
    refused(&f, &args, "--truth");
    refused(&f, &args, "pass --force to replace it");
    assert_eq!(std::fs::read(&truth).unwrap(), b"old");
    let o = run(&[&args[..], &["--force"]].concat());
    expect_code(&o, &[0], "simulate --force");
    assert_ne!(std::fs::read(&truth).unwrap(), b"old");
}

#[test]
fn a_folder_output_that_is_a_file_is_refused_by_name() {
    let f = Fixture::new();
    std::fs::write(f.p("x.mcap"), "taken").unwrap();
    let snap = Snapshot::of(&[f.dir.path()]);
    let (r, e, x) = (f.p("ref.tum"), f.p("est.tum"), f.p("x.mcap"));
    let says = "is a file, expected a folder; pass a new or existing folder";
    refused(&f, &["man", "--out", s(&r)], says);
    refused(
        &f,
        &[
            "simulate",
            s(&x),
            "--grandtour",
            "--force",
            "--duration",
            "5",
        ],
        says,
    );
    refused(&f, &eval_args(s(&f.p("in.mcap")), &["--plot", s(&e)]), says);
    refused(
        &f,
        &eval_args(s(&f.p("in.mcap")), &["--plot", "/dev/null"]),
        "/dev/null: is not a folder",
    );
    snap.assert_unchanged();
}

#[test]
fn restamp_refuses_the_audit_of_another_recording() {
    let f = Fixture::new();
    let (rec, audit, other) = (f.p("in.mcap"), f.p("a.json"), f.p("other.json"));
    let o = run(&["audit", s(&rec), "--json", s(&audit), "-q"]);
    expect_code(&o, &[0, 3], "audit");
    // The same audit, of a recording whose estimate is on another topic.
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(&audit).unwrap()).unwrap();
    for src in v["sources"].as_array_mut().unwrap() {
        if src["topic"] == "/estimate/odom" {
            src["topic"] = "/lio/odom".into();
        }
    }
    std::fs::write(&other, serde_json::to_vec(&v).unwrap()).unwrap();
    let out = f.p("r.mcap");
    let args = [
        "restamp",
        s(&rec),
        "--audit",
        s(&other),
        "--out",
        s(&out),
        "-q",
    ];
    refused(&f, &args, "an audit of another recording");
    refused(&f, &args, "/lio/odom");
    // Its own audit is taken.
    let o = run(&[
        "restamp",
        s(&rec),
        "--audit",
        s(&audit),
        "--out",
        s(&out),
        "-q",
    ]);
    expect_code(&o, &[0, 3], "restamp with its own audit");
    assert!(out.is_file());
}

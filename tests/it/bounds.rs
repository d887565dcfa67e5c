//! Bounded everything, at the process boundary: text from a pipe read once (no pose lost), lines,
//! manifests and presets with a size bound, FIFOs nobody writes into not waited on for ever, symlink
//! loops walked once, evo's range flags checked like eval's, one-pose trajectories refused cleanly.
//! No case may panic (exit 101) or hang; every input's bytes are unchanged.

use std::process::Output;
use std::time::{Duration, Instant};

use crate::robust_support::{
    eval_args, expect_code, mkfifo, run, s, stderr, stdout, Fixture, Snapshot,
};

/// Runs `args` through bash (for process substitution) in `dir`.
fn bash(dir: &std::path::Path, script: &str) -> Output {
    std::process::Command::new("bash")
        .arg("-c")
        .arg(script)
        .current_dir(dir)
        .env("TD", env!("CARGO_BIN_EXE_trajdrift"))
        .output()
        .unwrap()
}

#[test]
fn text_from_a_pipe_keeps_every_pose_and_lines_are_bounded() {
    let f = Fixture::new();
    let snap = Snapshot::of(&[f.dir.path()]);
    let poses = std::fs::read_to_string(f.p("est.tum"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .count();
    // The path is opened several times (format, header, rows): a pipe is read once and kept.
    let o = bash(f.dir.path(), "\"$TD\" export <(cat est.tum) piped.tum");
    expect_code(&o, &[0], "export <(cat est.tum)");
    let got = std::fs::read_to_string(f.p("piped.tum")).unwrap();
    assert_eq!(got.lines().filter(|l| !l.starts_with('#')).count(), poses);
    let o = bash(
        f.dir.path(),
        "\"$TD\" eval --reference-file <(cat ref.tum) --estimate-file <(cat est.tum) --time-offset 0.2 --json - -q",
    );
    expect_code(&o, &[0, 3], "eval of two pipes");
    let r: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(r["estimates"][0]["samples"], poses as u64);
    let o = bash(
        f.dir.path(),
        "\"$TD\" ape tum <(cat ref.tum) <(cat est.tum) --t_max_diff 0.05",
    );
    expect_code(&o, &[0], "ape of two pipes");
    // A file without a newline, and an endless one, end with a message.
    std::fs::write(f.p("oneline.tum"), vec![b'7'; 3 << 20]).unwrap();
    for input in [s(&f.p("oneline.tum")), "/dev/zero"] {
        let start = Instant::now();
        let o = run(&["export", input, s(&f.p("o.tum"))]);
        expect_code(&o, &[1], input);
        assert!(stderr(&o).contains("longer than 1 MiB"), "{}", stderr(&o));
        assert!(start.elapsed() < Duration::from_secs(10));
    }
    // A manifest or preset larger than any can be is refused by its size (sparse: nothing read).
    let rec = f.p("in.mcap");
    for (name, len, args) in [
        (
            "big.toml",
            17u64 << 20,
            vec!["batch", "BIG", "--out", "OUT"],
        ),
        (
            "preset.toml",
            2 << 20,
            vec!["eval", "IN", "--preset", "BIG", "-q"],
        ),
    ] {
        let big = f.p(name);
        std::fs::File::create(&big).unwrap().set_len(len).unwrap();
        let args: Vec<&str> = args
            .iter()
            .map(|a| match *a {
                "BIG" => s(&big),
                "OUT" => s(f.dir.path()),
                "IN" => s(&rec),
                a => a,
            })
            .collect();
        let o = run(&args);
        expect_code(&o, &[2], name);
        assert!(stderr(&o).contains("larger than"), "{}", stderr(&o));
        std::fs::remove_file(&big).unwrap();
    }
    snap.assert_unchanged();
}

#[test]
fn fifos_without_a_writer_and_symlink_loops_end() {
    let f = Fixture::new();
    let fifo = f.p("fifo");
    mkfifo(&fifo);
    let (rec, reference, o_dir) = (f.p("in.mcap"), f.p("ref.tum"), f.p("o"));
    let snap = Snapshot::of(&[&rec, &reference]);
    let cases: Vec<(Vec<&str>, i32, &str)> = vec![
        (
            vec!["eval", s(&fifo), "--reference", "/r", "--estimate", "/e"],
            2,
            "a recording is read with seeks",
        ),
        (vec!["eval", s(&rec), "--preset", s(&fifo)], 1, "no writer"),
        (vec!["batch", s(&fifo), "--out", s(&o_dir)], 1, "no writer"),
        (
            vec![
                "eval",
                "--reference-file",
                s(&reference),
                "--estimate-file",
                s(&fifo),
            ],
            1,
            "no writer",
        ),
    ];
    for (args, code, says) in cases {
        let start = Instant::now();
        let o = run(&args);
        expect_code(&o, &[code], says);
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert!(start.elapsed() < Duration::from_secs(20), "{args:?}");
    }
    // A folder holding a symlink to itself and one to its parent's view of it.
    let d = f.p("loop");
    std::fs::create_dir(&d).unwrap();
    std::fs::copy(f.p("in.mcap"), d.join("a.mcap")).unwrap();
    std::os::unix::fs::symlink(".", d.join("self")).unwrap();
    std::os::unix::fs::symlink("../loop", d.join("up")).unwrap();
    let o = run(&eval_args(s(&d), &[]));
    expect_code(&o, &[0, 3], "eval of a folder with a loop");
    let out = f.p("loop-out");
    let o = run(&[
        "batch",
        s(&d),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--time-offset",
        "0.2",
        "--out",
        s(&out),
        "-q",
    ]);
    expect_code(&o, &[0, 3], "batch of a folder with a loop");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["missions"], 1, "{summary}");
    snap.assert_unchanged();
}

#[test]
fn evo_flags_are_checked_like_evals_and_one_pose_is_refused() {
    let f = Fixture::new();
    let snap = Snapshot::of(&[f.dir.path()]);
    let (rp, ep) = (f.p("ref.tum"), f.p("est.tum"));
    let (r, e) = (s(&rp), s(&ep));
    let cases: [(&[&str], &str); 8] = [
        (
            &["ape", "tum", r, e, "--t_max_diff", "nan"],
            "--t_max_diff NaN",
        ),
        (
            &["ape", "tum", r, e, "--t_max_diff", "-1"],
            "--t_max_diff -1",
        ),
        (&["ape", "tum", r, e, "--t_offset", "inf"], "--t_offset inf"),
        (&["rpe", "tum", r, e, "-d", "0"], "--delta 0"),
        (&["rpe", "tum", r, e, "-d", "1.5"], "whole number"),
        (
            &["rpe", "tum", r, e, "--delta_tol", "-0.1"],
            "--delta_tol -0.1",
        ),
        (
            &["offset", "tum", r, e, "--spatial-range", "1e9"],
            "--spatial-range 1e9",
        ),
        (&["ape", "tum", r, e, "--n_to_align", "0"], "--n_to_align 0"),
    ];
    for (args, says) in cases {
        let start = Instant::now();
        let o = run(args);
        expect_code(&o, &[2], says);
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert!(start.elapsed() < Duration::from_secs(5));
    }
    // Every method failing is a failure (exit 1), not a table and exit 0.
    let far: String = std::fs::read_to_string(&ep)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let (t, rest) = l.split_once(' ').unwrap();
            format!("{:.9} {rest}\n", t.parse::<f64>().unwrap() + 1e5)
        })
        .collect();
    std::fs::write(f.p("far.tum"), far).unwrap();
    let o = run(&["offset", "tum", r, s(&f.p("far.tum"))]);
    expect_code(&o, &[1], "offset with every method failing");
    assert!(
        stderr(&o).contains("every offset method failed"),
        "{}",
        stderr(&o)
    );
    // One pose (and one stamp written twice): refused by name, never a panic.
    let text = std::fs::read_to_string(f.p("ref.tum")).unwrap();
    let first = text.lines().find(|l| !l.starts_with('#')).unwrap();
    std::fs::write(f.p("one.tum"), format!("{first}\n")).unwrap();
    std::fs::write(f.p("twice.tum"), format!("{first}\n{first}\n")).unwrap();
    for one in ["one.tum", "twice.tum"] {
        let one = f.p(one);
        let one = s(&one);
        for args in [
            vec!["ape", "tum", r, one],
            vec!["ape", "tum", one, one, "-a"],
            vec!["rpe", "tum", one, one, "-r", "point_distance"],
            vec![
                "ape",
                "--reference-file",
                one,
                "--estimate-file",
                one,
                "--sync_method",
                "interpolation",
            ],
            vec!["offset", "tum", one, one],
            vec!["offset", "--reference-file", r, "--estimate-file", one],
            vec!["offset", "--reference-file", one, "--estimate-file", one],
            vec!["eval", "--reference-file", one, "--estimate-file", e, "-q"],
        ] {
            let o = run(&args);
            expect_code(&o, &[1], &format!("{args:?}"));
            assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
            assert_eq!(stderr(&o).lines().count(), 1, "{args:?}: {}", stderr(&o));
        }
    }
    snap.assert_unchanged();
}

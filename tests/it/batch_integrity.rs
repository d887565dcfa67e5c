//! Batch results that cannot go stale and a merge that knows when its set is incomplete, at the
//! process boundary: `--skip-existing` re-runs exactly the missions whose parameters or inputs
//! changed; `merge` of a partial, mismatched or damaged set exits 1 naming what is wrong (and with
//! `--allow-partial` writes a summary marked partial); concurrent runs on one `--out` leave complete,
//! correct results and honest exit codes; `batch` exits 3 on a warning like `eval`. Every input's
//! bytes are unchanged after every case.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use crate::hostile_support::small_mcap;
use crate::robust_support::{expect_code, run, s, stderr, Snapshot};

/// Three small recordings (`recs/a.mcap`, `b.mcap`, `c.mcap`) and a manifest over them.
struct Batch {
    dir: tempfile::TempDir,
}

impl Batch {
    fn new() -> Batch {
        let dir = tempfile::tempdir().unwrap();
        let recs = dir.path().join("recs");
        std::fs::create_dir(&recs).unwrap();
        small_mcap(&recs.join("a.mcap"), 400);
        for m in ["b", "c"] {
            std::fs::copy(recs.join("a.mcap"), recs.join(format!("{m}.mcap"))).unwrap();
        }
        let b = Batch { dir };
        b.manifest("m.toml", &["a", "b", "c"], "");
        b
    }

    fn p(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Writes a manifest over `missions`; `b_params` goes into mission b's parameters.
    fn manifest(&self, name: &str, missions: &[&str], b_params: &str) -> PathBuf {
        let mut t = String::from("[defaults]\ntime_offset = 0.2\n");
        for m in missions {
            t.push_str(&format!(
                "\n[[mission]]\nname = \"{m}\"\nrecording = \"recs/{m}.mcap\"\nreference = \"/reference/position\"\nestimates = [\"/estimate/odom\"]\n"
            ));
            if *m == "b" && !b_params.is_empty() {
                t.push_str(&format!("[mission.parameters]\n{b_params}\n"));
            }
        }
        let p = self.p(name);
        std::fs::write(&p, t).unwrap();
        p
    }

    fn batch(&self, manifest: &str, out: &str, extra: &[&str]) -> std::process::Output {
        let manifest = self.p(manifest);
        let mut args = vec!["batch", s(&manifest), "--out"];
        let out = self.p(out);
        args.push(s(&out));
        args.push("-q");
        args.extend_from_slice(extra);
        run(&args)
    }
}

/// The inode of each mission's result: a result written again is a new file (renamed into place).
fn inodes(out: &Path, missions: &[&str]) -> Vec<u64> {
    missions
        .iter()
        .map(|m| {
            std::fs::metadata(out.join(format!("{m}.json")))
                .unwrap()
                .ino()
        })
        .collect()
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
        .unwrap()
}

#[test]
fn skip_existing_reruns_exactly_the_missions_whose_parameters_or_inputs_changed() {
    let b = Batch::new();
    let snap = Snapshot::of(&[&b.p("recs")]);
    let out = b.p("out");
    let all = ["a", "b", "c"];
    let o = b.batch("m.toml", "out", &[]);
    expect_code(&o, &[0, 3], "first run");
    let first = inodes(&out, &all);
    for m in all {
        let r = json(&out.join(format!("{m}.json")));
        assert_eq!(r["status"], "ok", "{m}");
        assert!(r["fingerprint"]["parameters"].is_string(), "{r}");
    }
    // Nothing changed: every result kept.
    let o = b.batch("m.toml", "out", &["--skip-existing"]);
    expect_code(&o, &[0, 3], "resume");
    assert_eq!(inodes(&out, &all), first);
    // Mission b's window changed: b alone runs again.
    b.manifest("m.toml", &all, "window = [10]");
    let o = b.batch("m.toml", "out", &["--skip-existing"]);
    expect_code(&o, &[0, 3], "b's window");
    let after = inodes(&out, &all);
    assert_eq!((after[0], after[2]), (first[0], first[2]));
    assert_ne!(after[1], first[1]);
    assert_eq!(
        json(&out.join("b.json"))["report"]["parameters"]["windows_m"],
        serde_json::json!([10.0])
    );
    // A parameter of every mission changed on the command line: all run again.
    let o = b.batch("m.toml", "out", &["--skip-existing", "--max-offset", "20"]);
    expect_code(&o, &[0, 3], "--max-offset");
    let all_new = inodes(&out, &all);
    assert!(all_new.iter().zip(&after).all(|(x, y)| x != y));
    snap.assert_unchanged();
    // c's recording replaced by other bytes of the same size and time: c alone runs again.
    let c = b.p("recs/c.mcap");
    let time = std::fs::metadata(&c).unwrap().modified().unwrap();
    let mut bytes = std::fs::read(&c).unwrap();
    let n = bytes.len();
    bytes[n - 40] ^= 0x01;
    std::fs::write(&c, &bytes).unwrap();
    std::fs::File::options()
        .write(true)
        .open(&c)
        .unwrap()
        .set_modified(time)
        .unwrap();
    let snap = Snapshot::of(&[&b.p("recs")]);
    let o = b.batch("m.toml", "out", &["--skip-existing", "--max-offset", "20"]);
    let again = inodes(&out, &all);
    assert_eq!(
        (again[0], again[1]),
        (all_new[0], all_new[1]),
        "{}",
        stderr(&o)
    );
    assert_ne!(again[2], all_new[2]);
    snap.assert_unchanged();
}

#[test]
fn merge_of_a_partial_mismatched_or_damaged_set_exits_1_naming_what_is_wrong() {
    let b = Batch::new();
    let snap = Snapshot::of(&[&b.p("recs"), &b.p("m.toml")]);
    for i in 1..=3 {
        let o = b.batch("m.toml", &format!("s{i}"), &["--shard", &format!("{i}/3")]);
        expect_code(&o, &[0, 3], "shard");
    }
    let merge = |dirs: &[&str], extra: &[&str]| {
        let mut args = vec!["merge".to_string()];
        args.extend(dirs.iter().map(|d| s(&b.p(d)).to_string()));
        args.extend(extra.iter().map(|x| x.to_string()));
        args.push("-q".into());
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        run(&args)
    };
    let complete = merge(&["s1", "s2", "s3"], &[]);
    expect_code(&complete, &[0, 3], "the whole set");
    let fails = |dirs: &[&str], says: &str| {
        let first = b.p(dirs[0]).join("summary.json");
        let _ = std::fs::remove_file(&first);
        let o = merge(dirs, &[]);
        expect_code(&o, &[1], says);
        assert!(stderr(&o).contains(says), "{says}: {}", stderr(&o));
        assert!(!first.exists(), "{says}: a summary was written");
    };
    // A missing shard.
    fails(&["s1", "s2"], "missing shard 3 of 3");
    // A shard run with other parameters.
    let o = b.batch("m.toml", "s3w", &["--shard", "3/3", "--window", "10"]);
    expect_code(&o, &[0, 3], "shard 3 with another window");
    fails(&["s1", "s2", "s3w"], "mismatched parameters");
    // A result cut short.
    let dmg = b.p("dmg");
    std::fs::create_dir(&dmg).unwrap();
    for d in ["s1", "s2", "s3"] {
        for e in std::fs::read_dir(b.p(d)).unwrap() {
            let p = e.unwrap().path();
            std::fs::copy(&p, dmg.join(p.file_name().unwrap())).unwrap();
        }
    }
    let a = dmg.join("a.json");
    let text = std::fs::read(&a).unwrap();
    std::fs::write(&a, &text[..text.len() / 2]).unwrap();
    fails(&["dmg"], "a.json: cannot parse");
    std::fs::write(&a, &text).unwrap();
    // A leftover of another run, a name that is no mission name, a file too large to be a result.
    std::fs::copy(b.p("s3w/c.json"), dmg.join("c.json")).unwrap();
    fails(&["dmg"], "mission `c` was computed with other parameters");
    std::fs::copy(b.p("s3/c.json"), dmg.join("c.json")).unwrap();
    let mut evil = json(&b.p("s1/a.json"));
    evil["mission"] = "javascript:alert(1)".into();
    let evil_path = dmg.join("javascript:alert(1).json");
    std::fs::write(&evil_path, serde_json::to_vec(&evil).unwrap()).unwrap();
    fails(&["dmg"], "is not a valid mission name");
    std::fs::remove_file(&evil_path).unwrap();
    let mut other = json(&b.p("s1/a.json"));
    other["mission"] = "d".into();
    std::fs::write(dmg.join("d.json"), serde_json::to_vec(&other).unwrap()).unwrap();
    fails(&["dmg"], "mission `d` is not in the run");
    std::fs::remove_file(dmg.join("d.json")).unwrap();
    let big = dmg.join("big.json");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(300 << 20)
        .unwrap();
    let start = std::time::Instant::now();
    fails(&["dmg"], "larger than 256 MiB");
    assert!(start.elapsed().as_secs() < 10);
    std::fs::remove_file(&big).unwrap();
    // A 100 MB JSON file that is not a result is skipped without holding it in memory.
    let mut huge = String::from("{\"kind\":\"something.else\",\"x\":[");
    huge.push_str(&"0,".repeat(50 << 20));
    huge.push_str("0]}");
    std::fs::write(dmg.join("huge.json"), huge).unwrap();
    let o = merge(&["dmg"], &[]);
    expect_code(&o, &[0, 3], "a large foreign JSON file");
    std::fs::remove_file(dmg.join("huge.json")).unwrap();
    // --allow-partial: written, marked partial, the problems listed; never exit 0.
    let o = merge(&["s1", "s2"], &["--allow-partial"]);
    expect_code(&o, &[3], "--allow-partial");
    let summary = json(&b.p("s1/summary.json"));
    assert_eq!(summary["partial"], true);
    assert!(summary["problems"][0]
        .as_str()
        .unwrap()
        .contains("missing shard 3 of 3"));
    let md = std::fs::read_to_string(b.p("s1/summary.md")).unwrap();
    assert!(md.contains("**Partial**"), "{md}");
    // Results without any run record (an older trajdrift's) are said to be unverifiable.
    let old = b.p("old");
    std::fs::create_dir(&old).unwrap();
    std::fs::copy(b.p("s1/a.json"), old.join("a.json")).unwrap();
    fails(&["old"], "no run record");
    snap.assert_unchanged();
}

#[test]
fn concurrent_runs_on_one_out_leave_complete_results_and_honest_exit_codes() {
    let b = Batch::new();
    let snap = Snapshot::of(&[&b.p("recs"), &b.p("m.toml")]);
    let out = b.p("out");
    std::fs::create_dir(&out).unwrap();
    // A run holding the folder: the second is refused before any work.
    let lock = std::fs::File::create(out.join(".trajdrift-batch.lock")).unwrap();
    // SAFETY: flock on a descriptor we own.
    assert_eq!(
        unsafe { libc::flock(std::os::unix::io::AsRawFd::as_raw_fd(&lock), libc::LOCK_EX) },
        0
    );
    let o = b.batch("m.toml", "out", &[]);
    expect_code(&o, &[2], "a folder in use");
    assert!(
        stderr(&o).contains("another trajdrift batch is writing into this folder"),
        "{}",
        stderr(&o)
    );
    assert!(!out.join("a.json").exists());
    drop(lock);
    // Two runs started at once: each finishes or is refused; the results are whole and `ok`.
    let spawn = |extra: &[&str]| {
        let mut c = crate::robust_support::bin();
        c.args([
            "batch",
            s(&b.p("m.toml")),
            "--out",
            s(&out),
            "-q",
            "--jobs",
            "1",
        ])
        .args(extra)
        .stderr(std::process::Stdio::piped());
        c.spawn().unwrap()
    };
    for extra in [&[][..], &["--skip-existing"][..]] {
        let (x, y) = (spawn(extra), spawn(extra));
        let outs = [x.wait_with_output().unwrap(), y.wait_with_output().unwrap()];
        let mut finished = 0;
        for o in &outs {
            match o.status.code() {
                Some(0 | 3) => finished += 1,
                Some(2) => assert!(
                    stderr(o).contains("another trajdrift batch"),
                    "{}",
                    stderr(o)
                ),
                c => panic!("exit {c:?}: {}", stderr(o)),
            }
        }
        assert!(finished >= 1);
        for m in ["a", "b", "c"] {
            assert_eq!(json(&out.join(format!("{m}.json")))["status"], "ok", "{m}");
        }
        let summary = json(&out.join("summary.json"));
        assert_eq!(summary["failed"], serde_json::json!([]));
    }
    // The shards of one run share the folder.
    let (x, y) = (spawn(&["--shard", "1/2"]), spawn(&["--shard", "2/2"]));
    for o in [x.wait_with_output().unwrap(), y.wait_with_output().unwrap()] {
        expect_code(&o, &[0, 3], "a shard");
    }
    let o = run(&["merge", s(&out), "-q"]);
    expect_code(&o, &[0, 3], "merge");
    // Re-running with --annotate over existing annotated copies is refused before any work instead of
    // turning good results into failures.
    let o = b.batch("m.toml", "ann", &["--annotate"]);
    expect_code(&o, &[0, 3], "--annotate");
    let before = std::fs::read(b.p("ann/a.json")).unwrap();
    let o = b.batch("m.toml", "ann", &["--annotate"]);
    expect_code(&o, &[2], "--annotate again");
    assert!(stderr(&o).contains("pass --force"), "{}", stderr(&o));
    assert_eq!(std::fs::read(b.p("ann/a.json")).unwrap(), before);
    let o = b.batch("m.toml", "ann", &["--annotate", "--skip-existing"]);
    expect_code(&o, &[0, 3], "--annotate --skip-existing");
    assert_eq!(std::fs::read(b.p("ann/a.json")).unwrap(), before);
    snap.assert_unchanged();
}

#[test]
fn batch_exits_like_eval_and_names_what_a_run_would_clash_with() {
    let b = Batch::new();
    // A truncated recording: eval exits 3, so does the batch, and the summary says which mission.
    let a = std::fs::read(b.p("recs/a.mcap")).unwrap();
    std::fs::write(b.p("recs/b.mcap"), &a[..a.len() * 2 / 3]).unwrap();
    let snap = Snapshot::of(&[&b.p("recs"), &b.p("m.toml")]);
    let e = run(&[
        "eval",
        s(&b.p("recs/b.mcap")),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--time-offset",
        "0.2",
        "-q",
    ]);
    expect_code(&e, &[3], "eval of a truncated recording");
    let o = b.batch("m.toml", "out", &[]);
    expect_code(&o, &[3], "batch with a truncated recording");
    assert!(
        stderr(&o).contains("warning [truncated_recording]: mission b"),
        "{}",
        stderr(&o)
    );
    let summary = json(&b.p("out/summary.json"));
    let warned = summary["warned"].as_array().unwrap();
    assert!(
        warned.iter().any(|w| w["mission"] == "b"
            && w["warnings"]
                .as_array()
                .unwrap()
                .contains(&"truncated_recording".into())),
        "{summary}"
    );
    let md = std::fs::read_to_string(b.p("out/summary.md")).unwrap();
    assert!(md.contains("Missions with a warning"), "{md}");
    // A recording named summary.mcap would lose its result to the summary: refused before any work.
    std::fs::copy(b.p("recs/a.mcap"), b.p("recs/summary.mcap")).unwrap();
    let o = run(&[
        "batch",
        s(&b.p("recs")),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--out",
        s(&b.p("out2")),
        "-q",
    ]);
    expect_code(&o, &[2], "a mission named summary");
    assert!(
        stderr(&o).contains("mission `summary`") && stderr(&o).contains("the batch summary"),
        "{}",
        stderr(&o)
    );
    assert!(!b.p("out2/summary.json").exists());
    std::fs::remove_file(b.p("recs/summary.mcap")).unwrap();
    // --out inside the folder of recordings: refused.
    let o = run(&[
        "batch",
        s(&b.p("recs")),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--out",
        s(&b.p("recs/results")),
        "-q",
    ]);
    expect_code(&o, &[2], "--out inside the input folder");
    assert!(!b.p("recs/results").exists());
    // A Slurm array given as a list of indices is refused, not mapped onto the wrong shards.
    let o = crate::robust_support::bin()
        .args([
            "batch",
            s(&b.p("m.toml")),
            "--out",
            s(&b.p("out3")),
            "--shard",
            "auto",
        ])
        .env("SLURM_ARRAY_TASK_ID", "3")
        .env("SLURM_ARRAY_TASK_MIN", "1")
        .env("SLURM_ARRAY_TASK_MAX", "7")
        .env("SLURM_ARRAY_TASK_COUNT", "3")
        .env("SLURM_ARRAY_TASK_STEP", "1")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .unwrap();
    expect_code(&o, &[2], "a Slurm list array");
    assert!(stderr(&o).contains("--array=1,3,7"), "{}", stderr(&o));
    // --jobs far beyond the work runs (capped by the missions), every result whole.
    let o = b.batch("m.toml", "out4", &["--jobs", "100000"]);
    expect_code(&o, &[0, 3], "--jobs 100000");
    // Manifest mistakes are usage errors at load time naming the key and the mission.
    b.manifest("bad.toml", &["a", "b"], "max_offset = 1e9");
    let o = b.batch("bad.toml", "out5", &[]);
    expect_code(&o, &[2], "max_offset out of range");
    assert!(
        stderr(&o).contains("mission b: [mission.parameters]: max_offset 1e9"),
        "{}",
        stderr(&o)
    );
    assert!(!b.p("out5").exists());
    let mut list = String::from("[defaults]\nwindow = [");
    for i in 0..100_000 {
        list.push_str(&format!("{},", 1.0 + i as f64 * 0.01));
    }
    list.push_str(
        "1]\n[[mission]]\nrecording = \"recs/a.mcap\"\nreference = \"/r\"\nestimates = [\"/e\"]\n",
    );
    std::fs::write(b.p("big.toml"), list).unwrap();
    let o = b.batch("big.toml", "out6", &[]);
    expect_code(&o, &[2], "a window list of 100 000");
    assert!(
        stderr(&o).contains("[defaults]: window: 100000 sizes"),
        "{}",
        stderr(&o)
    );
    snap.assert_unchanged();
}

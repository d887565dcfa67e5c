//! `trajdrift batch` and `merge` over the shared missions plus one broken entry: results identical
//! whatever `--jobs`, the broken mission reported while the others are done, shards merged equal to
//! one run, `--skip-existing` resumes.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn batch(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .arg("batch")
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap()
}

/// A JSON file without its machine-dependent `timing` object.
fn load(path: &Path) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if let Some(o) = v.as_object_mut() {
        o.remove("timing");
    }
    v
}

fn manifest(shared: &Path, dir: &Path) -> std::path::PathBuf {
    // Explicit parameters: the test does not depend on the defaults; a given offset keeps it fast.
    let mut text = String::from("[defaults]\ntime_offset = 0.2\nwindow = [5]\n");
    for m in common::MISSIONS {
        text.push_str(&format!(
            "\n[[mission]]\nname = \"{m}\"\nrecording = \"{}\"\nreference = \"/reference/position\"\nestimates = [\"/estimate/odom\", \"pose=/estimate/pose\"]\n",
            common::mission(shared, m).join("mission.mcap").display()
        ));
    }
    text.push_str("\n[[mission]]\nname = \"broken\"\nrecording = \"missing.mcap\"\nreference = \"/reference/position\"\nestimates = [\"/estimate/odom\"]\n");
    let p = dir.join("missions.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn jobs_shards_merge_and_resume_give_the_same_results() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = manifest(&shared, d);
    let ms = m.to_str().unwrap();
    let out = |n: &str| d.join(n).to_str().unwrap().to_string();

    let one = batch(&[ms, "--jobs", "1", "--out", &out("j1")]);
    let two = batch(&[ms, "--jobs", "2", "--out", &out("j2")]);
    assert_eq!(one.status.code(), Some(1), "a mission failed → exit 1");
    assert_eq!(two.status.code(), Some(1));
    for name in common::MISSIONS.iter().chain(&["broken", "summary"]) {
        let f = format!("{name}.json");
        assert_eq!(
            load(&d.join("j1").join(&f)),
            load(&d.join("j2").join(&f)),
            "{f}"
        );
    }
    for f in ["summary.csv", "summary.md"] {
        assert_eq!(
            std::fs::read(d.join("j1").join(f)).unwrap(),
            std::fs::read(d.join("j2").join(f)).unwrap(),
            "{f}"
        );
    }
    let summary = load(&d.join("j1/summary.json"));
    assert_eq!(summary["missions"], 6);
    assert_eq!(summary["failed"][0]["mission"], "broken");
    assert!(summary["failed"][0]["error"]
        .as_str()
        .unwrap()
        .contains("missing.mcap"));
    let odom = summary["estimates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["estimate"] == "estimate/odom")
        .unwrap();
    assert_eq!(odom["n"], 5);
    assert!(odom["de_rmse_iqr"].as_f64().unwrap() >= 0.0);
    assert_eq!(odom["missions"][0]["dt_s"], 0.2);

    // Shards 1/2 and 2/2, merged, equal the single run.
    let s1 = batch(&[ms, "--jobs", "2", "--shard", "1/2", "--out", &out("s1")]);
    let s2 = batch(&[ms, "--jobs", "2", "--shard", "2/2", "--out", &out("s2")]);
    assert!(s1.status.code().is_some() && s2.status.code().is_some());
    let merged = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args([
            "merge",
            &out("s1"),
            &out("s2"),
            "--quiet",
            "--out",
            &out("merged"),
        ])
        .output()
        .unwrap();
    assert_eq!(merged.status.code(), Some(1));
    assert_eq!(
        load(&d.join("merged/summary.json")),
        load(&d.join("j1/summary.json"))
    );
    assert_eq!(
        std::fs::read(d.join("merged/summary.csv")).unwrap(),
        std::fs::read(d.join("j1/summary.csv")).unwrap()
    );

    // Resume: done missions are kept (their JSON untouched), the failed one is retried.
    let before = std::fs::metadata(d.join("j1/straight.json"))
        .unwrap()
        .modified()
        .unwrap();
    let again = batch(&[ms, "--skip-existing", "--out", &out("j1")]);
    assert_eq!(again.status.code(), Some(1));
    let after = std::fs::metadata(d.join("j1/straight.json"))
        .unwrap()
        .modified()
        .unwrap();
    assert_eq!(before, after);
    assert_eq!(
        load(&d.join("j1/summary.json")),
        load(&d.join("j2/summary.json"))
    );
}

#[test]
fn a_folder_of_recordings_with_annotate() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let recs = dir.path().join("recs");
    std::fs::create_dir(&recs).unwrap();
    for m in ["straight", "legged"] {
        std::fs::copy(
            common::mission(&shared, m).join("mission.mcap"),
            recs.join(format!("{m}.mcap")),
        )
        .unwrap();
    }
    let out = dir.path().join("out");
    let o = batch(&[
        recs.to_str().unwrap(),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--annotate",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        matches!(o.status.code(), Some(0) | Some(3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for m in ["straight", "legged"] {
        assert!(out.join(format!("{m}.mcap")).exists());
        let r = load(&out.join(format!("{m}.json")));
        assert_eq!(r["status"], "ok");
        assert_eq!(r["annotated"], format!("{m}.mcap"));
    }
    // Missing topics for a folder: a usage error.
    let bad = batch(&[recs.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(2));
}

/// `--shard auto` under a scheduler's variables: two tasks write into ONE output folder (each its own
/// `summary-shard-I-of-2.*`, no clash), and `merge` of that folder equals the whole run.
#[test]
fn shard_auto_under_slurm_and_kubernetes_merges_to_the_whole_run() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = manifest(&shared, d);
    let ms = m.to_str().unwrap();
    let out = |n: &str| d.join(n).to_str().unwrap().to_string();
    let whole = batch(&[ms, "--jobs", "2", "--out", &out("whole")]);
    assert_eq!(whole.status.code(), Some(1));

    type Vars = Vec<(&'static str, String)>;
    let slurm = |task: &str| -> Vars {
        vec![
            ("SLURM_ARRAY_TASK_ID", task.to_string()),
            ("SLURM_ARRAY_TASK_MIN", "0".into()),
            ("SLURM_ARRAY_TASK_COUNT", "2".into()),
        ]
    };
    let kube = |index: &str| -> Vars {
        vec![
            ("JOB_COMPLETION_INDEX", index.to_string()),
            ("TRAJDRIFT_SHARDS", "2".into()),
        ]
    };
    let runs: [(&str, [Vars; 2]); 2] = [
        ("slurm", [slurm("0"), slurm("1")]),
        ("kube", [kube("0"), kube("1")]),
    ];
    for (name, tasks) in runs {
        let folder = out(name);
        for vars in tasks {
            let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
                .args(["batch", ms, "--jobs", "1", "--shard", "auto", "--quiet"])
                .args(["--out", &folder])
                .env_remove("SLURM_ARRAY_TASK_ID")
                .env_remove("JOB_COMPLETION_INDEX")
                .envs(vars)
                .output()
                .unwrap();
            assert!(
                matches!(o.status.code(), Some(0 | 1 | 3)),
                "{name}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        for i in 1..=2 {
            assert!(d
                .join(name)
                .join(format!("summary-shard-{i}-of-2.json"))
                .exists());
        }
        assert!(!d.join(name).join("summary.json").exists());
        let merged = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
            .args(["merge", &folder, "--quiet"])
            .output()
            .unwrap();
        assert_eq!(merged.status.code(), Some(1), "{name}: the broken mission");
        assert_eq!(
            load(&d.join(name).join("summary.json")),
            load(&d.join("whole/summary.json")),
            "{name}"
        );
    }

    let none = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(["batch", ms, "--shard", "auto", "--out", &out("none")])
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .unwrap();
    assert_eq!(none.status.code(), Some(2));
}

/// Every kind of mission in one folder — an MCAP, a ROS 1 bag, a rosbag2 folder and a mission folder
/// of bags — evaluated with `batch`'s flags; then the same values through a manifest.
#[test]
fn a_folder_of_every_kind_takes_evals_flags_and_a_manifest_the_same() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let missions = d.join("missions");
    std::fs::create_dir_all(missions.join("folder")).unwrap();
    let fx = |m: &str, f: &str| common::mission(&shared, m).join(f);
    let link = |from: PathBuf, to: PathBuf| std::os::unix::fs::symlink(from, to).unwrap();
    link(fx("lever_arm", "mission.mcap"), missions.join("a.mcap"));
    link(fx("legged", "mission_ros1.bag"), missions.join("b.bag"));
    link(fx("gnss_outages", "rosbag2"), missions.join("c"));
    link(
        fx("lever_arm", "mission_ros1.bag"),
        missions.join("folder/d.bag"),
    );
    let check = |out: &Path, names: &[&str]| {
        for name in names {
            let r = load(&out.join(format!("{name}.json")));
            assert_eq!(r["status"], "ok", "{name}: {}", r["error"]);
            let p = &r["report"]["parameters"];
            assert_eq!(p["windows_m"], serde_json::json!([5.0, 10.0]), "{name}");
            assert_eq!(p["offset_method"], "speed", "{name}");
        }
    };
    let out = d.join("out-flags");
    let o = batch(&[
        missions.to_str().unwrap(),
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--window",
        "5,10",
        "--offset-method",
        "speed",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    check(&out, &["a", "b", "c", "folder"]);

    let manifest = d.join("m.toml");
    let mut text = String::from("[defaults]\nwindow = [5, 10]\noffset_method = \"speed\"\n");
    for (name, rec) in [
        ("a", "a.mcap"),
        ("b", "b.bag"),
        ("c", "c"),
        ("folder", "folder"),
    ] {
        text.push_str(&format!(
            "\n[[mission]]\nname = \"{name}\"\nrecording = \"missions/{rec}\"\nreference = \"/reference/position\"\nestimates = [\"/estimate/odom\"]\n"
        ));
    }
    std::fs::write(&manifest, text).unwrap();
    let out_m = d.join("out-manifest");
    let o = batch(&[manifest.to_str().unwrap(), "--out", out_m.to_str().unwrap()]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    check(&out_m, &["a", "b", "c", "folder"]);
    for name in ["a", "b", "c", "folder"] {
        let f = format!("{name}.json");
        let (x, y) = (load(&out.join(&f)), load(&out_m.join(&f)));
        assert_eq!(x["report"]["estimates"], y["report"]["estimates"], "{name}");
    }
}

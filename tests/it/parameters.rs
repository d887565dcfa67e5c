//! One parameter model: every evaluation parameter, enumerated from the parameter table (so a new one
//! cannot be forgotten here), gives the same report through an `eval` flag, a batch manifest's
//! `[defaults]` and a preset's `[parameters]`; a batch's flags apply to every mission, over the
//! manifest's values.

use std::path::{Path, PathBuf};
use std::process::Command;

use trajdrift::params::SPECS;

/// A value for each parameter: (as a flag, as TOML). A parameter missing here fails the test.
fn example(id: &str) -> Option<(&'static str, &'static str)> {
    Some(match id {
        "stamp" => ("log", "\"log\""),
        "origin" => ("47.0,8.0,400.0", "[47.0, 8.0, 400.0]"),
        "platform" => ("wheeled", "\"wheeled\""),
        "eps_min" => ("0.5", "0.5"),
        "curvature_eps" => ("1.5", "1.5"),
        "path_eps" => ("0.8", "0.8"),
        "theta_max" => ("1.2", "1.2"),
        "dt_max" => ("3", "3.0"),
        "window" => ("5,10", "[5, 10]"),
        "overlap" => ("0.5", "0.5"),
        "lever_correction" => ("paper", "\"paper\""),
        "lever_arm" => ("0.2", "0.2"),
        "offset_method" => ("signed-curvature", "\"signed-curvature\""),
        "max_offset" => ("10", "10.0"),
        "grid" => ("0.002", "0.002"),
        "time_offset" => ("-0.25", "-0.25"),
        "t_start" => ("5", "5.0"),
        "t_end" => ("60", "60.0"),
        "offset_model" => ("piecewise", "\"piecewise\""),
        "offset_refine" => ("none", "\"none\""),
        "offset_window" => ("30", "30.0"),
        "offset_step" => ("5", "5.0"),
        "metrics" => ("de,kitti", "[\"de\", \"kitti\"]"),
        _ => return None,
    })
}

fn recording() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/sim_ground/mission.mcap")
}

fn trajdrift(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(args)
        .output()
        .unwrap()
}

fn json(bytes: &[u8], what: &str) -> serde_json::Value {
    serde_json::from_slice(bytes).unwrap_or_else(|e| panic!("{what}: {e}"))
}

fn by_flag(id: &str, value: &str) -> serde_json::Value {
    let rec = recording();
    let flag = format!("--{}", id.replace('_', "-"));
    let o = trajdrift(&[
        "eval",
        rec.to_str().unwrap(),
        "--reference",
        "/reference/position",
        "--estimate",
        "odom=/estimate/odom",
        "--quiet",
        "--json",
        "-",
        &flag,
        value,
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "{flag} {value}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    json(&o.stdout, &flag)
}

fn by_preset(dir: &Path, id: &str, value: &str) -> serde_json::Value {
    let preset = dir.join(format!("preset-{id}.toml"));
    std::fs::write(
        &preset,
        format!(
            "name = \"p\"\ndescription = \"test\"\nrobot = \"wheeled\"\n[reference]\ntopics = [\"/reference/position\"]\n[[estimate]]\nname = \"odom\"\ntopics = [\"/estimate/odom\"]\n[parameters]\n{id} = {value}\n"
        ),
    )
    .unwrap();
    let rec = recording();
    let o = trajdrift(&[
        "eval",
        rec.to_str().unwrap(),
        "--preset",
        preset.to_str().unwrap(),
        "--quiet",
        "--json",
        "-",
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "preset {id} = {value}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    json(&o.stdout, "preset")
}

fn by_manifest(dir: &Path, id: &str, value: &str, flags: &[&str]) -> serde_json::Value {
    let manifest = dir.join(format!("missions-{id}.toml"));
    std::fs::write(
        &manifest,
        format!(
            "[defaults]\n{id} = {value}\n\n[[mission]]\nname = \"m\"\nrecording = \"{}\"\nreference = \"/reference/position\"\nestimates = [\"odom=/estimate/odom\"]\n",
            recording().display()
        ),
    )
    .unwrap();
    let out = dir.join(format!("out-{id}"));
    let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(["batch", manifest.to_str().unwrap(), "--quiet", "--out"])
        .arg(&out)
        .args(flags)
        .output()
        .unwrap();
    assert!(
        matches!(o.status.code(), Some(0 | 3)),
        "manifest {id} = {value}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let mut r = json(&std::fs::read(out.join("m.json")).unwrap(), "m.json");
    r["report"].take()
}

#[test]
fn every_parameter_is_the_same_through_flag_manifest_and_preset() {
    let dir = tempfile::tempdir().unwrap();
    let defaults = by_flag("window", "5");
    let mut n = 0;
    for spec in SPECS {
        let id = spec.key;
        let (flag, toml) = example(id).unwrap_or_else(|| {
            panic!("parameter {id} has no example in tests/parameters.rs: add one")
        });
        let from_flag = by_flag(id, flag);
        assert_ne!(
            from_flag, defaults,
            "{id}: the example must change the report"
        );
        assert_eq!(
            from_flag,
            by_manifest(dir.path(), id, toml, &[]),
            "{id}: manifest"
        );
        assert_eq!(from_flag, by_preset(dir.path(), id, toml), "{id}: preset");
        n += 1;
    }
    assert!(n >= 22, "only {n} parameters enumerated");
}

#[test]
fn batch_flags_apply_to_every_mission_over_the_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let from_flags = by_flag("window", "5,10");
    let over = by_manifest(dir.path(), "window", "[20]", &["--window", "5,10"]);
    assert_eq!(over, from_flags);
    assert_eq!(
        over["parameters"]["windows_m"],
        serde_json::json!([5.0, 10.0])
    );
}

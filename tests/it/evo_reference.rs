//! evo's own numbers: every row of `shared/evo-data/REFERENCE.md` (evo 1.38.1 on real trajectories) is
//! run with `trajdrift` in place of `evo_`, at the process boundary, and its seven statistics must equal
//! evo's six printed decimals. Then the one-line errors of the standard metrics.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn evo_data() -> Option<PathBuf> {
    common::shared().map(|s| s.join("evo-data"))
}

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run trajdrift")
}

/// The rows of REFERENCE.md's table: (command, [rmse, mean, median, std, min, max, sse] as printed).
fn rows(dir: &Path) -> Vec<(String, Vec<String>)> {
    let text = std::fs::read_to_string(dir.join("REFERENCE.md")).expect("REFERENCE.md");
    text.lines()
        .filter(|l| l.starts_with("| `evo_"))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            let cmd = cells[1].trim_matches('`').to_string();
            (cmd, cells[2..9].iter().map(|s| s.to_string()).collect())
        })
        .collect()
}

/// The statistics trajdrift printed, in REFERENCE.md's column order.
fn printed_stats(stdout: &str) -> Vec<String> {
    ["rmse", "mean", "median", "std", "min", "max", "sse"]
        .iter()
        .map(|name| {
            stdout
                .lines()
                .find_map(|l| {
                    let mut it = l.split_whitespace();
                    (it.next() == Some(name)).then(|| it.next().unwrap_or("").to_string())
                })
                .unwrap_or_else(|| format!("<no {name}>"))
        })
        .collect()
}

#[test]
fn every_reference_row_equals_evo_to_six_decimals() {
    let Some(dir) = evo_data() else { return };
    let rows = rows(&dir);
    assert!(rows.len() >= 17, "{} rows in REFERENCE.md", rows.len());
    let mut failures = Vec::new();
    for (cmd, want) in &rows {
        let args: Vec<&str> = cmd.split_whitespace().collect();
        let sub = args[0].strip_prefix("evo_").expect("an evo_ command");
        let mut full = vec![sub];
        full.extend(&args[1..]);
        let out = run_in(&dir, &full);
        let stdout = String::from_utf8_lossy(&out.stdout);
        let got = printed_stats(&stdout);
        if !out.status.success() || &got != want {
            failures.push(format!(
                "trajdrift {}: got {got:?}, evo {want:?}; stderr: {}",
                full.join(" "),
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn json_carries_the_same_numbers() {
    let Some(dir) = evo_data() else { return };
    let out = run_in(
        &dir,
        &[
            "ape",
            "tum",
            "fr2_desk_groundtruth.txt",
            "fr2_desk_ORB.txt",
            "-a",
            "--json",
            "-",
        ],
    );
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    assert_eq!(v["metric"], "ape");
    assert_eq!(v["relation"], "trans_part");
    assert_eq!(v["alignment"]["method"], "se3");
    assert_eq!(
        format!("{:.6}", v["stats"]["rmse"].as_f64().unwrap()),
        "0.008119"
    );
    assert_eq!(v["stats"]["n"], v["pairs"]);
}

/// The motivating example: S-PTAM in KITTI 00 lags one frame; `--time-offset auto` finds it and evo's
/// APE drops from 3.738 to 3.590 m.
#[test]
fn time_offset_auto_finds_the_sptam_lag() {
    let Some(dir) = evo_data() else { return };
    let base = [
        "ape",
        "--reference-file",
        "KITTI_00_gt.txt",
        "--estimate-file",
        "KITTI_00_SPTAM.txt",
        "--kitti-times",
        "KITTI_00_gt_times.txt",
        "-a",
    ];
    let rmse = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend(extra);
        let out = run_in(&dir, &a);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        printed_stats(&String::from_utf8_lossy(&out.stdout))[0].clone()
    };
    assert_eq!(rmse(&[]), "3.738488");
    assert_eq!(rmse(&["--time-offset", "auto"]), "3.590356");
}

fn one_line_error(dir: &Path, args: &[&str], codes: &[i32], needle: &str) {
    let out = run_in(dir, args);
    let err = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code().unwrap_or(-1);
    assert!(codes.contains(&code), "{args:?}: exit {code}, {err}");
    assert!(err.contains(needle), "{args:?}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn no_pairs_names_the_clock_difference() {
    let Some(dir) = evo_data() else { return };
    one_line_error(
        &dir,
        &[
            "ape",
            "tum",
            "fr2_desk_groundtruth.txt",
            "fr2_desk_ORB.txt",
            "--t_offset",
            "100",
        ],
        &[1],
        "0 pairs within t_max_diff 0.01 s; the clocks differ by about -100.",
    );
}

#[test]
fn mismatched_formats_say_which_form_to_use() {
    let Some(dir) = evo_data() else { return };
    one_line_error(
        &dir,
        &["ape", "tum", "KITTI_00_gt.txt", "KITTI_00_ORB.txt"],
        &[2],
        "looks like KITTI (12 values a row); use kitti",
    );
    one_line_error(
        &dir,
        &[
            "rpe",
            "kitti",
            "fr2_desk_groundtruth.txt",
            "fr2_desk_ORB.txt",
        ],
        &[2],
        "looks like TUM",
    );
}

#[test]
fn degenerate_alignment_and_position_only_data_are_one_line_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let mut still = String::new();
    let mut moving = String::new();
    let mut points = String::new();
    for i in 0..50 {
        let t = i as f64 * 0.1;
        still += &format!("{t:.1} 1 2 3 0 0 0 1\n");
        moving += &format!("{t:.1} {} {} 0 0 0 0 1\n", t.cos(), t.sin());
        points += &format!("{t:.1} {} {} 0\n", t.cos(), t.sin());
    }
    std::fs::write(dir.join("still.txt"), still).unwrap();
    std::fs::write(dir.join("moving.txt"), moving).unwrap();
    std::fs::write(dir.join("points.txt"), points).unwrap();
    one_line_error(
        dir,
        &["ape", "tum", "moving.txt", "still.txt", "-a"],
        &[1],
        "degenerate covariance rank",
    );
    one_line_error(
        dir,
        &["ape", "tum", "moving.txt", "points.txt", "-r", "angle_deg"],
        &[1, 2],
        "-r angle_deg needs orientations",
    );
    one_line_error(
        dir,
        &["rpe", "tum", "points.txt", "moving.txt", "-r", "full"],
        &[1, 2],
        "needs orientations",
    );
    // Positions alone are enough for the translation part and point distances.
    let out = run_in(
        dir,
        &[
            "rpe",
            "tum",
            "moving.txt",
            "points.txt",
            "-r",
            "point_distance",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `eval --metrics`: evo's APE/RPE and KITTI drift on the time-aligned estimate, beside Drift Error.
#[test]
fn eval_reports_ape_rpe_and_kitti_beside_drift_error() {
    let Some(dir) = evo_data() else { return };
    let out = run_in(
        &dir,
        &[
            "eval",
            "--reference-file",
            "KITTI_00_gt.txt",
            "--estimate-file",
            "KITTI_00_SPTAM.txt",
            "--kitti-times",
            "KITTI_00_gt_times.txt",
            "--metrics",
            "de,ape,rpe,kitti",
            "--json",
            "-",
        ],
    );
    assert!(out.status.code() == Some(0) || out.status.code() == Some(3));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let e = &v["estimates"][0];
    assert!(!e["drift_error"].as_array().unwrap().is_empty());
    let m = &e["standard_metrics"];
    let ape = m["ape"]["stats"]["rmse"].as_f64().unwrap();
    assert!(
        (ape - 3.590).abs() < 0.005,
        "APE {ape} on the time-aligned S-PTAM"
    );
    assert!(m["rpe_1m"]["stats"]["rmse"].as_f64().unwrap() > 0.0);
    assert!(m["rpe_point_distance_1m"]["pairs"].as_u64().unwrap() > 1000);
    let k = &m["kitti"];
    assert_eq!(k["per_length"].as_array().unwrap().len(), 8);
    assert!(k["t_err_pct"].as_f64().unwrap() > 0.0);
    // Only Drift Error: no standard metrics in the report.
    let out = run_in(
        &dir,
        &[
            "eval",
            "--reference-file",
            "KITTI_00_gt.txt",
            "--estimate-file",
            "KITTI_00_SPTAM.txt",
            "--kitti-times",
            "KITTI_00_gt_times.txt",
            "--metrics",
            "de",
            "--json",
            "-",
        ],
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert!(v["estimates"][0].get("standard_metrics").is_none());
}

/// `trajdrift offset`: the six methods in one table; on S-PTAM the correlation methods find the one
/// frame lag and shifting by it lowers the APE.
#[test]
fn offset_compares_every_method() {
    let Some(dir) = evo_data() else { return };
    let out = run_in(
        &dir,
        &[
            "offset",
            "--reference-file",
            "KITTI_00_gt.txt",
            "--estimate-file",
            "KITTI_00_SPTAM.txt",
            "--kitti-times",
            "KITTI_00_gt_times.txt",
            "--json",
            "-",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).expect("JSON");
    let names: Vec<&str> = rows.iter().map(|r| r["method"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "none",
            "spatial",
            "speed",
            "curvature",
            "signed-curvature",
            "auto"
        ]
    );
    let ape = |m: &str| {
        rows.iter().find(|r| r["method"] == m).unwrap()["ape_rmse_m"]
            .as_f64()
            .unwrap()
    };
    let dt = rows.iter().find(|r| r["method"] == "speed").unwrap()["offset_s"]
        .as_f64()
        .unwrap();
    assert!((dt - 0.104).abs() < 0.01, "speed Δt {dt}");
    assert!(ape("speed") < ape("none") && ape("spatial") <= ape("speed") + 1e-9);
}

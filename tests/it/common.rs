//! Helpers shared by the integration tests: where `shared/` is, and its fixtures' truth.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use nalgebra::Vector3;

/// The five shared missions.
pub const MISSIONS: [&str; 5] = [
    "lever_arm",
    "gnss_outages",
    "legged",
    "legged_spins",
    "straight",
];

/// `$TRAJDRIFT_SHARED` (default `../shared`). In CI (`CI` or `TRAJDRIFT_SHARED` set) a missing folder
/// fails the test; on a developer machine without it the test is skipped with a message.
pub fn shared() -> Option<PathBuf> {
    let explicit = std::env::var("TRAJDRIFT_SHARED").ok();
    let dir = explicit
        .clone()
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    if dir.join("fixtures").is_dir() {
        return Some(dir);
    }
    if explicit.is_some() || std::env::var_os("CI").is_some() {
        panic!(
            "shared data missing at {} (TRAJDRIFT_SHARED); CI must have it",
            dir.display()
        );
    }
    eprintln!(
        "skipped: shared data not found at {} (set TRAJDRIFT_SHARED)",
        dir.display()
    );
    None
}

/// A mission's folder.
pub fn mission(shared: &Path, name: &str) -> PathBuf {
    shared.join("fixtures").join(name)
}

/// A mission's truth.json.
pub fn truth(shared: &Path, name: &str) -> serde_json::Value {
    let p = mission(shared, name).join("truth.json");
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// A mission's reference.tum and estimate.tum, times in seconds from the reference's first stamp.
pub struct Mission {
    pub truth: serde_json::Value,
    pub ref_t: Vec<f64>,
    pub ref_p: Vec<Vector3<f64>>,
    /// The estimate's stamps on its own clock.
    pub est_t: Vec<f64>,
    /// The same shifted by the true offset onto the reference's clock (est_t + dt_true).
    pub est_t_on_ref_clock: Vec<f64>,
    pub est_p: Vec<Vector3<f64>>,
    /// truth.json `time_offset.dt_true_s`.
    pub dt_true: f64,
    /// Reference's first stamp minus truth.json `start_time_ns`, seconds.
    pub ref_origin_s: f64,
}

/// Reads a mission's TUM files and truth.
pub fn load(shared: &Path, name: &str) -> Mission {
    let dir = mission(shared, name);
    let truth = truth(shared, name);
    let dt_true = truth["time_offset"]["dt_true_s"]
        .as_f64()
        .expect("time_offset.dt_true_s");
    let start_ns = truth["start_time_ns"].as_i64().expect("start_time_ns");
    let read = |f: &str| {
        trajdrift::sources::tum::read_tum(&dir.join(f))
            .unwrap_or_else(|e| panic!("{}: {e}", dir.join(f).display()))
    };
    let (r, e) = (read("reference.tum"), read("estimate.tum"));
    let t0 = r.stamps_ns[0];
    let est_t = e.times_s(t0);
    Mission {
        ref_t: r.times_s(t0),
        ref_p: r.positions,
        est_t_on_ref_clock: est_t.iter().map(|t| t + dt_true).collect(),
        est_t,
        est_p: e.positions,
        dt_true,
        ref_origin_s: (t0 - start_ns) as f64 * 1e-9,
        truth,
    }
}

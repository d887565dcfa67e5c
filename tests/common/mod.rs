//! Helpers shared by the integration tests: where `shared/` is, and its fixtures' truth.
#![allow(dead_code)]

use std::path::PathBuf;

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
pub fn mission(shared: &std::path::Path, name: &str) -> PathBuf {
    shared.join("fixtures").join(name)
}

/// A mission's truth.json.
pub fn truth(shared: &std::path::Path, name: &str) -> serde_json::Value {
    let p = mission(shared, name).join("truth.json");
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

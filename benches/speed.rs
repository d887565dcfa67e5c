//! Speed benchmark: wall time of the library's whole evaluation (read, offset search with every method,
//! Drift Error at 1, 5, 10 and 20 m) on each shared mission, and on a long simulated mission.
//!
//! `cargo bench --bench speed` (reads `$TRAJDRIFT_SHARED`, default `../shared`).

use std::path::PathBuf;
use std::time::Instant;

use trajdrift::eval::config::{EvalConfig, NamedInput};
use trajdrift::eval::evaluate;

fn main() {
    let shared = std::env::var("TRAJDRIFT_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    for m in [
        "lever_arm",
        "gnss_outages",
        "legged",
        "legged_spins",
        "straight",
    ] {
        let rec = shared.join("fixtures").join(m).join("mission.mcap");
        if !rec.exists() {
            eprintln!("speed: {} missing, skipped", rec.display());
            continue;
        }
        let mut c = EvalConfig::new(
            Some(rec),
            NamedInput::topic("/reference/position"),
            vec![NamedInput::topic("/estimate/odom")],
        );
        c.windows_m = vec![1.0, 5.0, 10.0, 20.0];
        let reps = 3;
        let start = Instant::now();
        for _ in 0..reps {
            let r = evaluate(&c, &|_| {});
            if let Err(e) = r {
                eprintln!("speed: {m}: {e}");
            }
        }
        println!(
            "speed: {m:<13} {:8.1} ms per eval",
            start.elapsed().as_secs_f64() * 1e3 / reps as f64
        );
    }
}

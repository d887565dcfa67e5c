//! `trajdrift offset`: the clock-offset methods side by side, one table (or JSON).

use anyhow::Result;

use trajdrift::output::{is_stdout, write_json};
use trajdrift::standard::offsets::compare_offset_methods;

use crate::cli::args::OffsetArgs;
use crate::cli::EXIT_OK;

/// Runs the command; returns the exit code.
pub fn run(a: OffsetArgs) -> Result<u8> {
    let inputs = super::metric::inputs(&a.common)?;
    let guard = super::metric::claim_json(&a.common)?;
    let config = inputs.offset_config()?;
    let rows = compare_offset_methods(&config, a.spatial_range)?;
    let to_stdout = a.common.json.as_deref().is_some_and(is_stdout);
    if let Some(path) = &a.common.json {
        guard.check("--json", path)?;
        write_json(path, &rows)?;
    }
    if !to_stdout {
        let opt = |v: Option<f64>, w: usize, d: usize| {
            v.map_or_else(|| format!("{:>w$}", "-"), |x| format!("{x:>w$.d$}"))
        };
        println!(
            "{:<17} {:>10} {:>9} {:>7} {:>10} {:>13}",
            "method", "Δt (s)", "quality", "status", "time (ms)", "APE rmse (m)"
        );
        for r in &rows {
            println!(
                "{:<17} {} {} {:>7} {:>10.1} {}{}",
                r.method,
                opt(r.offset_s, 10, 4),
                opt(r.quality, 9, 4),
                r.status,
                r.time_ms,
                opt(r.ape_rmse_m, 13, 4),
                r.error
                    .as_deref()
                    .map_or(String::new(), |e| format!("  {e}"))
            );
        }
        println!("quality: peak NCC for speed/curvature/signed-curvature/auto, the APE rmse (m) for spatial");
    }
    Ok(EXIT_OK)
}

//! `trajdrift offset`: the clock-offset methods side by side, one table (or JSON).

use anyhow::Result;

use trajdrift::output::{is_stdout, write_json};
use trajdrift::report::escape::escape;
use trajdrift::standard::offsets::{compare_offset_methods, OffsetRow, OffsetWay};

use crate::cli::args::OffsetArgs;

/// The widest spatial search: 6000 APE evaluations at 0.1 s.
const MAX_SPATIAL_RANGE_S: f64 = 300.0;

/// Runs the command; returns the exit code: 1 when every method failed, 3 when none is confident or
/// the recording was cut short.
pub fn run(a: OffsetArgs) -> Result<u8> {
    super::metric::validate(&a.common)?;
    // The command finds Δt every way it can; an offset given beside it would be silently unused.
    for (flag, given) in [
        ("--time-offset", a.common.time_offset.is_some()),
        ("--t_offset", a.common.t_offset.is_some()),
    ] {
        if given {
            return Err(trajdrift::Error::InvalidArgument(format!(
                "{flag}: `offset` finds the clock offset by every method and takes none; drop {flag} (ape, rpe and eval take one)"
            ))
            .into());
        }
    }
    trajdrift::params::Range {
        min: trajdrift::params::Bound::Exclusive(0.0),
        max: trajdrift::params::Bound::Inclusive(MAX_SPATIAL_RANGE_S),
        unit: "s",
    }
    .check("--spatial-range", a.spatial_range)?;
    let inputs = super::metric::inputs(&a.common)?;
    let guard = super::metric::claim_json(&a.common)?;
    let config = inputs.offset_config()?;
    let (rows, warnings) = compare_offset_methods(&config, a.spatial_range)?;
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
                    .map_or(String::new(), |e| format!("  {}", escape(e)))
            );
        }
        println!("quality: peak NCC for speed/curvature/signed-curvature/auto, the APE rmse (m) for spatial");
    }
    let methods: Vec<&OffsetRow> = rows
        .iter()
        .filter(|r| r.method != OffsetWay::None)
        .collect();
    if methods.iter().all(|r| r.offset_s.is_none()) {
        let first = methods
            .iter()
            .find_map(|r| {
                r.error
                    .as_deref()
                    .map(|e| format!("{}: {}", r.method, escape(e)))
            })
            .unwrap_or_default();
        return Err(trajdrift::Error::Metric(format!(
            "every offset method failed (each one's reason is in its row; {first})"
        ))
        .into());
    }
    for w in &warnings {
        crate::cli::warn(w);
    }
    Ok(crate::cli::exit_code(&warnings))
}

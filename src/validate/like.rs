//! `trajdrift validate --like RECORDING`: the accuracy to expect on the user's own recording.
//!
//! The recording's reference and estimate are read (the evaluation's one pass), their shape taken
//! ([`crate::simulate::like::shape_of`]: the reference's route, both rates and noise levels, the
//! outages, legged or wheeled), and missions of that shape with known clock offsets injected are
//! simulated and graded with every default, exactly as the calibration table's missions are
//! ([`super::run_scenario`]). The table says how far the Δt of an evaluation of this recording is
//! to be trusted, and whether its σ means what it says there.

use rayon::prelude::*;

use super::{calibration, run_scenario, MissionGrade};
use crate::error::{Error, Result};
use crate::eval::config::EvalConfig;
use crate::eval::inputs::load;
use crate::simulate::like::{scenario_like, shape_of, Shape};
use crate::sources::{Progress, Warning};

/// The grades of `missions` missions shaped like `shape` (seeds `first_seed` …), in seed order.
pub fn run_like(
    shape: &Shape,
    missions: usize,
    first_seed: u64,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Vec<MissionGrade> {
    let done = std::sync::atomic::AtomicUsize::new(0);
    (0..missions as u64)
        .into_par_iter()
        .map(|i| {
            let mut g = run_scenario(&scenario_like(shape, first_seed + i));
            g.kind = "like".into();
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(n, missions);
            g
        })
        .collect()
}

/// The shape of the recording and the estimate of `config` (its first estimate), and what the read
/// warns of (a recording cut short).
pub fn recording_shape(
    config: &EvalConfig,
    progress: Progress<'_>,
) -> Result<(Shape, Vec<Warning>)> {
    let inputs = load(config, progress)?;
    // The missions are simulated over the recording's span and searched like it: a span the
    // evaluation refuses (a bad stamp years late) is refused here, before anything is simulated.
    crate::eval::check_search_size(config, &inputs)?;
    let estimate = inputs.estimates.first().ok_or_else(|| {
        Error::InvalidArgument("validate --like needs one --estimate".to_string())
    })?;
    let shape = shape_of(&inputs.reference.trajectory, &estimate.trajectory).ok_or_else(|| {
        Error::InvalidArgument(format!(
            "{}: the reference {} and the estimate {} need 10 samples each and 30 s of reference to take their shape from",
            inputs.path, inputs.reference.label, estimate.label
        ))
    })?;
    Ok((shape, inputs.warnings))
}

/// What the user reads: the shape taken from the recording, then the accuracy on missions of it.
pub fn like_table(shape: &Shape, grades: &[MissionGrade]) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let moving = shape.route.iter().filter(|l| l.speed_mps > 0.0).count();
    let spins = shape.route.iter().filter(|l| l.spin_rps != 0.0).count();
    let _ = writeln!(
        out,
        "shape of the recording: {:.0} s, reference {:.1} Hz (noise {:.1} mm, {} outage(s)), estimate {:.1} Hz (noise {:.1} mm); moving {:.0} % of the time at {:.2} m/s (median), {} s turning in place; simulated as a {} robot",
        shape.duration_s,
        shape.ref_rate_hz,
        shape.ref_noise_m * 1e3,
        shape.outages.len(),
        shape.est_rate_hz,
        shape.est_noise_m * 1e3,
        100.0 * moving as f64 / shape.route.len().max(1) as f64,
        shape.moving_speed_mps,
        spins,
        if shape.legged { "legged" } else { "wheeled" },
    );
    let refs: Vec<&MissionGrade> = grades.iter().collect();
    let c = calibration(&refs);
    let sigma: Vec<f64> = grades.iter().filter_map(|g| g.sigma_s).collect();
    let median_sigma = crate::stats::median(&sigma).unwrap_or(f64::NAN);
    let _ = writeln!(
        out,
        "\n| missions | applied | |error| p50 / p90 / max ms | median σ ms | 2σ covers | median |error|/σ | clock alarms |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|");
    let _ = writeln!(
        out,
        "| {} | {} | {:.1} / {:.1} / {:.1} | {:.1} | {:.0} % | {:.2} | {} |",
        c.missions,
        c.applied,
        c.error_p50_s * 1e3,
        c.error_p90_s * 1e3,
        c.error_max_s * 1e3,
        median_sigma * 1e3,
        100.0 * c.coverage_2sigma,
        c.median_error_over_sigma,
        c.clock_alarms
    );
    let _ = writeln!(
        out,
        "\nEach mission: this route, these rates and noise levels, a known constant clock offset of −2…2 s; the lever arm, scale error, heading drift{} drawn from the seed.",
        if shape.legged { ", gait" } else { "" }
    );
    out
}

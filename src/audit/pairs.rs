//! Every pair's clock offset, by the evaluation itself.
//!
//! The sources were read in one pass; each pair (A, B) that overlaps in time is evaluated like
//! `trajdrift eval` with A as the reference and B as the estimate ([`crate::eval::evaluate_loaded`]
//! on the loaded trajectories: the offset search, its σ, the clock model), so whatever the evaluation
//! knows about clocks — and every improvement to it — the audit knows too. The reference's pairs are
//! evaluated with every metric asked (Drift Error, APE, …); the other pairs with the clock only.
//! Pairs run in parallel; each holds a copy of its two trajectories while it runs.

use rayon::prelude::*;

use crate::eval::config::{EvalConfig, NamedInput, TrajectoryInput};
use crate::eval::inputs::{Inputs, Loaded};
use crate::report::json::{EstimateReport, Report};

/// The shortest overlap, seconds, on which a pair is evaluated.
pub const MIN_OVERLAP_S: f64 = 10.0;

/// One pair's evaluation: the report of B against A (or why there is none).
#[derive(Debug, Clone)]
pub struct PairEvaluation {
    pub a: usize,
    pub b: usize,
    /// Seconds both have data (on their own clocks).
    pub overlap_s: f64,
    pub result: Result<(EstimateReport, Report), String>,
}

/// Seconds both trajectories have data, stamps as read.
pub fn overlap_s(a: &Loaded, b: &Loaded) -> f64 {
    match (a.trajectory.span_ns(), b.trajectory.span_ns()) {
        (Some((a0, a1)), Some((b0, b1))) => (a1.min(b1) - a0.max(b0)).max(0) as f64 * 1e-9,
        _ => 0.0,
    }
}

/// The configuration of pair (A, B): the audit's parameters, with A as the reference; `clock_only`
/// drops the metrics (only the clock is wanted). The crop is absolute already.
fn pair_config(base: &EvalConfig, a: &Loaded, b: &Loaded, clock_only: bool) -> EvalConfig {
    let named = |l: &Loaded| NamedInput {
        name: l.name.clone(),
        input: TrajectoryInput::Topic(l.label.clone()),
    };
    let mut c = EvalConfig::new(base.recording.clone(), named(a), vec![named(b)]);
    c.more_recordings = base.more_recordings.clone();
    c.params = base.params.clone();
    if clock_only {
        c.params.metrics = Some(Vec::new());
    }
    c
}

/// Evaluates every pair (i < j) of `sources` (the reference at index 0) whose spans overlap by
/// [`MIN_OVERLAP_S`] or more.
pub fn evaluate_pairs(base: &EvalConfig, sources: &[Loaded]) -> Vec<PairEvaluation> {
    let mut pairs = Vec::new();
    for a in 0..sources.len() {
        for b in a + 1..sources.len() {
            pairs.push((a, b));
        }
    }
    pairs
        .par_iter()
        .map(|&(a, b)| {
            let overlap = overlap_s(&sources[a], &sources[b]);
            let result = if overlap < MIN_OVERLAP_S {
                Err(format!(
                    "{} and {} overlap {overlap:.1} s (less than {MIN_OVERLAP_S} s)",
                    sources[a].name, sources[b].name
                ))
            } else {
                let config = pair_config(base, &sources[a], &sources[b], a != 0);
                let inputs = Inputs {
                    reference: sources[a].clone(),
                    estimates: vec![sources[b].clone()],
                    warnings: Vec::new(),
                    path: base
                        .recording
                        .as_ref()
                        .map(|p| p.display().to_string())
                        .unwrap_or_default(),
                    bytes: 0,
                };
                crate::eval::evaluate_loaded(&config, inputs)
                    .map_err(|e| e.to_string())
                    .and_then(|(report, _)| match report.estimates.first() {
                        Some(e) => Ok((e.clone(), report)),
                        None => Err("no result".into()),
                    })
            };
            PairEvaluation {
                a,
                b,
                overlap_s: overlap,
                result,
            }
        })
        .collect()
}

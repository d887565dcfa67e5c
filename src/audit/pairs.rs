//! Every pair's clock offset, by the evaluation itself.
//!
//! The sources were read in one pass; each pair (A, B) that overlaps in time is evaluated like
//! `trajdrift eval` with A as the reference and B as the estimate ([`crate::eval::evaluate_loaded`]
//! on the loaded trajectories: the offset search, its σ, the clock model), so whatever the evaluation
//! knows about clocks — and every improvement to it — the audit knows too. The reference's pairs are
//! evaluated with every metric asked (Drift Error, APE, …); the other pairs with the clock only.
//! The reference's pairs run first; every other pair is then measured between its two sources'
//! streams mapped onto the reference's clock, where their relative clock is a small constant
//! residual ([`super::chain`]: what makes a drifting source against a stepping one measurable, and
//! the search short). Pairs run in parallel; each holds a copy of its two trajectories while it
//! runs.

use rayon::prelude::*;

use super::report::PairMeasurement;
use crate::clock::ClockCorrection;
use crate::eval::config::{EvalConfig, NamedInput, TrajectoryInput};
use crate::eval::inputs::{Inputs, Loaded};
use crate::report::json::{EstimateReport, OffsetSource, Report, TimeOffsetStatus};

/// The shortest overlap, seconds, on which a pair is evaluated.
pub const MIN_OVERLAP_S: f64 = 10.0;

/// One pair's evaluation: the report of B against A (or why there is none).
#[derive(Debug, Clone)]
pub struct PairEvaluation {
    pub a: usize,
    pub b: usize,
    /// Seconds both have data (on their own clocks).
    pub overlap_s: f64,
    /// How it was measured: through the reference's clock, `result` is the residual of the two
    /// sources' streams on it ([`super::chain`]), not their clock.
    pub measured: PairMeasurement,
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

/// Evaluates the reference's pair with every other source (`sources[0]` the reference) whose span
/// overlaps it by [`MIN_OVERLAP_S`] or more.
pub fn reference_pairs(base: &EvalConfig, sources: &[Loaded]) -> Vec<PairEvaluation> {
    (1..sources.len())
        .into_par_iter()
        .map(|b| evaluate_pair(base, sources, (0, b), None))
        .collect()
}

/// Evaluates every other pair (1 ≤ i < j) that overlaps by [`MIN_OVERLAP_S`] or more, given the
/// reference's pairs: through the reference's clock ([`super::chain`]) when both its sources have a
/// confident clock against the reference, directly otherwise.
pub fn other_pairs(
    base: &EvalConfig,
    sources: &[Loaded],
    reference_pairs: &[PairEvaluation],
) -> Vec<PairEvaluation> {
    let n = sources.len();
    // Each source's stamps on the reference's clock, where its clock against the reference is
    // confident.
    let mapped: Vec<(usize, Loaded)> = reference_pairs
        .par_iter()
        .filter_map(|e| {
            let (r, _) = e.result.as_ref().ok()?;
            (r.time_offset.status == TimeOffsetStatus::Ok).then(|| {
                let correction = ClockCorrection::from_report(&r.time_offset);
                let t = correction.apply(&sources[e.b].trajectory);
                (e.b, sources[e.b].with_trajectory(t))
            })
        })
        .collect();
    let mut on_reference: Vec<Option<Loaded>> = vec![None; n];
    for (b, l) in mapped {
        on_reference[b] = Some(l);
    }
    let mut others = Vec::new();
    for a in 1..n {
        for b in a + 1..n {
            others.push((a, b));
        }
    }
    others
        .par_iter()
        .map(|&(a, b)| match (&on_reference[a], &on_reference[b]) {
            (Some(ca), Some(cb)) => evaluate_pair(base, sources, (a, b), Some((ca, cb))),
            _ => evaluate_pair(base, sources, (a, b), None),
        })
        .collect()
}

/// B (`lb`) evaluated against A (`la`) with `config`.
fn evaluate_one(
    base: &EvalConfig,
    config: &EvalConfig,
    la: &Loaded,
    lb: &Loaded,
) -> Result<(EstimateReport, Report), String> {
    let inputs = Inputs {
        reference: la.clone(),
        estimates: vec![lb.clone()],
        warnings: Vec::new(),
        path: base
            .recording
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        bytes: 0,
    };
    crate::eval::evaluate_loaded(config, inputs)
        .map_err(|e| e.to_string())
        .and_then(|(report, _)| match report.estimates.first() {
            Some(e) => Ok((e.clone(), report)),
            None => Err("no result".into()),
        })
}

/// The highest rate, Hz, of the reference role of a pair measured through the reference: its
/// residual is wanted about as precisely as the sources' clocks against the reference, whose pose
/// fits see windows of some 200 points (a 10 Hz total station or GNSS over 20 s); a 50 Hz odometry
/// in that role would cost five times as much for a sharper closure than its chains can use.
pub const CHAINED_MAX_RATE_HZ: f64 = 10.0;

/// `l` with every k-th sample kept so that its median rate is at most `max_hz`; `None` when it is
/// already.
fn thinned(l: &Loaded, max_hz: f64) -> Option<Loaded> {
    let period_s = l.trajectory.median_period_s()?;
    let k = (1.0 / (period_s * max_hz)).ceil();
    if !(k.is_finite() && k >= 2.0) {
        return None;
    }
    let k = k as usize;
    let t = &l.trajectory;
    let mut out = crate::trajectory::Trajectory::new(t.orientations.is_some());
    for i in (0..t.len()).step_by(k) {
        out.push(
            t.stamps_ns[i],
            t.positions[i],
            t.orientations.as_ref().map(|q| q[i]),
        );
    }
    Some(l.with_trajectory(out))
}

/// Pair (a, b) evaluated, on the stamps as read or on `chained` (both on the reference's clock).
fn evaluate_pair(
    base: &EvalConfig,
    sources: &[Loaded],
    (a, b): (usize, usize),
    chained: Option<(&Loaded, &Loaded)>,
) -> PairEvaluation {
    let overlap = overlap_s(&sources[a], &sources[b]);
    let result = if overlap < MIN_OVERLAP_S {
        Err(format!(
            "{} and {} overlap {overlap:.1} s (less than {MIN_OVERLAP_S} s)",
            sources[a].name, sources[b].name
        ))
    } else {
        // On one clock, the reference role thinned (the pose fit visits each of its samples).
        let thin = chained.and_then(|(ca, _)| thinned(ca, CHAINED_MAX_RATE_HZ));
        let (la, lb) = match chained {
            Some((ca, cb)) => (thin.as_ref().unwrap_or(ca), cb),
            None => (&sources[a], &sources[b]),
        };
        let mut config = pair_config(base, la, lb, a != 0);
        // On one clock the residual is near 0: the pose fit starts there, without the searches;
        // should it fail, the pair is searched like any other.
        config.start_offset_s = chained.map(|_| 0.0);
        let mut result = evaluate_one(base, &config, la, lb);
        let fitted = |r: &Result<(EstimateReport, Report), String>| {
            r.as_ref()
                .is_ok_and(|(e, _)| e.time_offset.method == OffsetSource::Pose)
        };
        if config.start_offset_s.is_some() && !fitted(&result) {
            config.start_offset_s = None;
            result = evaluate_one(base, &config, la, lb);
        }
        result
    };
    PairEvaluation {
        a,
        b,
        overlap_s: overlap,
        measured: match chained {
            Some(_) => PairMeasurement::ThroughReference,
            None => PairMeasurement::Direct,
        },
        result,
    }
}

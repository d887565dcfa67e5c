//! `trajdrift validate`: how far to trust the time alignment, measured on missions whose truth is
//! known.
//!
//! Each mission of [`crate::simulate::scenario`] (every [`MissionKind`], fixed seeds) is evaluated
//! in memory with all defaults — the same `eval::evaluate_loaded` as `trajdrift eval` — and
//! graded against its clock's truth: the headline Δt's error and whether its σ covers it, each profile
//! window's, the clock model chosen (a drift or step warning on a constant clock is a false alarm),
//! the drift and the steps recovered. [`table`] prints the calibration table. [`like`] does the same
//! on missions shaped like the user's own recording (`trajdrift validate --like`).

pub mod like;

use rayon::prelude::*;

use crate::align::clock_model::OffsetModel;
use crate::align::pose_model::SigmaParts;
use crate::diag::WarningCode;
use crate::error::Result;
use crate::eval::config::{EvalConfig, NamedInput};
use crate::eval::inputs::{Inputs, Loaded};
use crate::report::json::{OffsetSource, Report, TimeOffsetReport, TimeOffsetStatus};
use crate::simulate::scenario::{MissionKind, Scenario, START_NS};
use crate::trajectory::Trajectory;

/// What to run.
#[derive(Debug, Clone)]
pub struct ValidateOptions {
    /// Missions of each kind.
    pub per_kind: usize,
    /// The kinds (all when empty).
    pub kinds: Vec<MissionKind>,
    /// The first seed; mission i of a kind has seed `first_seed + i`.
    pub first_seed: u64,
}

impl Default for ValidateOptions {
    fn default() -> Self {
        ValidateOptions {
            per_kind: 10,
            kinds: MissionKind::ALL.to_vec(),
            first_seed: 1,
        }
    }
}

/// The truth of a validation mission: Δt as a function of reference time (seconds from the
/// reference's first stamp), and the clock's rate error and step.
pub trait ClockTruth: Sync {
    /// Δt at reference time `t` (seconds from the mission's start).
    fn offset_at(&self, t: f64) -> f64;
    /// The clock's rate error, ppm (0: none).
    fn drift_ppm(&self) -> f64 {
        0.0
    }
    /// The step's time (seconds from the start) and the offsets before and after it.
    fn step(&self) -> Option<(f64, f64, f64)> {
        None
    }
}

impl ClockTruth for Scenario {
    fn offset_at(&self, t: f64) -> f64 {
        Scenario::offset_at(self, t)
    }

    fn drift_ppm(&self) -> f64 {
        self.clock_drift_ppm
    }

    fn step(&self) -> Option<(f64, f64, f64)> {
        self.clock_step.map(|s| {
            (
                s.at_s,
                self.offset_at(s.at_s - 1e-9),
                self.offset_at(s.at_s),
            )
        })
    }
}

/// One profile window against the truth.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct WindowGrade {
    pub error_s: f64,
    pub sigma_s: f64,
}

/// One mission's grade.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MissionGrade {
    pub kind: String,
    pub seed: u64,
    pub legged: bool,
    pub ref_rate_hz: f64,
    pub est_rate_hz: f64,
    pub est_lever_m: [f64; 3],
    /// `ok` or `weak`; absent when the evaluation failed (`error` says why).
    pub status: Option<TimeOffsetStatus>,
    /// The evaluation's error, if it failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub method: Option<OffsetSource>,
    pub model: Option<OffsetModel>,
    /// The headline Δt's error against the truth at the time it states (constant: the truth at the
    /// middle of the overlap; linear: at `t_mid`; piecewise: the longest segment's), seconds.
    pub error_s: Option<f64>,
    pub sigma_s: Option<f64>,
    /// What σ was made of (the report's `time_offset.sigma_parts`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma_parts: Option<SigmaParts>,
    /// The truth's largest distance from the headline Δt over the mission (a drift the constant hides).
    pub spread_s: f64,
    pub windows: Vec<WindowGrade>,
    /// A drift or step warning.
    pub clock_alarm: bool,
    pub drift_true_ppm: f64,
    pub drift_ppm: Option<f64>,
    pub drift_measured_ppm: Option<f64>,
    /// The reported drift's σ (linear: the fit's; otherwise the profile line's), ppm.
    pub drift_sigma_ppm: Option<f64>,
    pub drift_resolution_ppm: Option<f64>,
    /// Steps: the located change time's error (s) and the segments' largest error (s).
    pub step_time_error_s: Option<f64>,
    pub step_segment_error_s: Option<f64>,
    pub warnings: Vec<WarningCode>,
}

/// Evaluates `reference` and `estimate` (stamps in ns, the estimate on its own clock) with every
/// default, as `trajdrift eval` would: the same `eval::evaluate_loaded`.
pub fn evaluate_pair(reference: Trajectory, estimate: Trajectory) -> Result<Report> {
    let config = EvalConfig::new(
        None,
        NamedInput::file("reference"),
        vec![NamedInput::file("estimate")],
    );
    let loaded = |name: &str, trajectory: Trajectory| Loaded {
        name: name.into(),
        label: name.into(),
        type_name: "simulated".into(),
        trajectory,
        dropped_samples: 0,
        rows: Default::default(),
        geodetic_origin: None,
        lever_m: None,
    };
    let inputs = Inputs {
        reference: loaded("reference", reference),
        estimates: vec![loaded("estimate", estimate)],
        warnings: Vec::new(),
        path: "simulated".into(),
        bytes: 0,
    };
    crate::eval::evaluate_loaded(&config, inputs).map(|(r, _)| r)
}

/// Grades the report of a mission whose clock is `truth`; `t0_s` is the truth's time origin in the
/// report's absolute seconds.
pub fn grade(truth: &dyn ClockTruth, report: &Report, t0_s: f64) -> MissionGrade {
    let e = &report.estimates[0];
    let o: &TimeOffsetReport = &e.time_offset;
    let windows = window_grades(truth, o, t0_s);
    let (a, b) = overlap_s(o, t0_s);
    let ok = o.status == TimeOffsetStatus::Ok;
    let headline_t = headline_t_s(o, t0_s, (a, b));
    let error_s = ok.then(|| o.offset_s - truth.offset_at(headline_t));
    let spread_s = [a, b]
        .iter()
        .map(|&t| (truth.offset_at(t) - truth.offset_at(headline_t)).abs())
        .fold(0.0, f64::max);
    let (step_time_error_s, step_segment_error_s) = step_errors_s(truth, o, t0_s);
    let codes: Vec<WarningCode> = report.warnings.iter().map(|w| w.code).collect();
    MissionGrade {
        kind: String::new(),
        seed: 0,
        legged: false,
        ref_rate_hz: 0.0,
        est_rate_hz: 0.0,
        est_lever_m: [0.0; 3],
        status: Some(o.status),
        error: None,
        method: Some(o.method),
        model: o.model,
        error_s,
        sigma_s: o.sigma_s,
        sigma_parts: o.sigma_parts,
        spread_s,
        windows,
        clock_alarm: codes.iter().any(|w| {
            matches!(
                w,
                WarningCode::ClockDriftSuspected | WarningCode::ClockStepSuspected
            )
        }),
        drift_true_ppm: truth.drift_ppm(),
        drift_ppm: o.drift_ppm,
        drift_measured_ppm: o.drift_measured_ppm,
        drift_sigma_ppm: o.drift_sigma_ppm,
        drift_resolution_ppm: o.drift_resolution_ppm,
        step_time_error_s,
        step_segment_error_s,
        warnings: codes,
    }
}

/// Each profile window with a finite σ against the truth at its time.
fn window_grades(truth: &dyn ClockTruth, o: &TimeOffsetReport, t0_s: f64) -> Vec<WindowGrade> {
    o.profile
        .iter()
        .filter(|w| w.sigma_s.is_finite())
        .map(|w| WindowGrade {
            error_s: w.offset_s - truth.offset_at(w.t - t0_s),
            sigma_s: w.sigma_s,
        })
        .collect()
}

/// The span of the overlap, seconds from the truth's origin: from the first profile window's start
/// to the last one's end (0, 0 without a profile).
fn overlap_s(o: &TimeOffsetReport, t0_s: f64) -> (f64, f64) {
    match (o.profile.first(), o.profile.last(), o.profile_window_s) {
        (Some(f), Some(l), Some(w)) => (f.t - t0_s - 0.5 * w, l.t - t0_s + 0.5 * w),
        _ => (0.0, 0.0),
    }
}

/// The time the headline Δt states, seconds from the truth's origin: a linear model's `t_mid`, the
/// middle of a piecewise model's longest segment, else the middle of the overlap `(a, b)`.
fn headline_t_s(o: &TimeOffsetReport, t0_s: f64, (a, b): (f64, f64)) -> f64 {
    match o.model {
        Some(OffsetModel::Linear) => o.t_mid.map_or(0.5 * (a + b), |t| t - t0_s),
        Some(OffsetModel::Piecewise) => o
            .segments
            .iter()
            .max_by(|x, y| (x.t_end - x.t_start).total_cmp(&(y.t_end - y.t_start)))
            .map_or(0.5 * (a + b), |s| 0.5 * (s.t_start + s.t_end) - t0_s),
        _ => 0.5 * (a + b),
    }
}

/// A step recovered by a piecewise model: the located change's error against the true step time
/// (the change nearest to it) and the segments' largest offset error, seconds (none without a true
/// step or a piecewise model of two segments or more).
fn step_errors_s(
    truth: &dyn ClockTruth,
    o: &TimeOffsetReport,
    t0_s: f64,
) -> (Option<f64>, Option<f64>) {
    match truth.step() {
        Some((at, before, after))
            if o.model == Some(OffsetModel::Piecewise) && o.segments.len() >= 2 =>
        {
            let change = o.segments[1..]
                .iter()
                .map(|s| s.t_start - t0_s - at)
                .min_by(|x, y| x.abs().total_cmp(&y.abs()));
            let seg = o
                .segments
                .iter()
                .map(|s| {
                    let mid = 0.5 * (s.t_start + s.t_end) - t0_s;
                    (s.offset_s - if mid < at { before } else { after }).abs()
                })
                .fold(0.0, f64::max);
            (change, Some(seg))
        }
        _ => (None, None),
    }
}

/// Simulates and grades one mission.
pub fn run_one(kind: MissionKind, seed: u64) -> MissionGrade {
    run_scenario(&Scenario::draw(kind, seed))
}

/// Simulates and grades the mission `s`.
pub fn run_scenario(s: &Scenario) -> MissionGrade {
    let seed = s.seed;
    let m = s.simulate();
    let t0_s = START_NS as f64 * 1e-9;
    let mut g = match evaluate_pair(m.reference, m.estimate) {
        Ok(report) => grade(s, &report, t0_s),
        Err(e) => MissionGrade {
            kind: String::new(),
            seed,
            legged: s.legged,
            ref_rate_hz: 0.0,
            est_rate_hz: 0.0,
            est_lever_m: [0.0; 3],
            status: None,
            error: Some(e.to_string()),
            method: None,
            model: None,
            error_s: None,
            sigma_s: None,
            sigma_parts: None,
            spread_s: 0.0,
            windows: Vec::new(),
            clock_alarm: false,
            drift_true_ppm: s.clock_drift_ppm,
            drift_ppm: None,
            drift_measured_ppm: None,
            drift_sigma_ppm: None,
            drift_resolution_ppm: None,
            step_time_error_s: None,
            step_segment_error_s: None,
            warnings: Vec::new(),
        },
    };
    g.kind = s.kind.as_str().into();
    g.seed = seed;
    g.legged = s.legged;
    g.ref_rate_hz = s.ref_rate_hz;
    g.est_rate_hz = s.est_rate_hz;
    g.est_lever_m = s.est_lever_m;
    g
}

/// Runs every mission of `options` (in parallel; the grades in kind, then seed order).
pub fn run(
    options: &ValidateOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Vec<MissionGrade> {
    let kinds = if options.kinds.is_empty() {
        MissionKind::ALL.to_vec()
    } else {
        options.kinds.clone()
    };
    let jobs: Vec<(MissionKind, u64)> = kinds
        .iter()
        .flat_map(|&k| (0..options.per_kind as u64).map(move |i| (k, options.first_seed + i)))
        .collect();
    let done = std::sync::atomic::AtomicUsize::new(0);
    jobs.par_iter()
        .map(|&(k, seed)| {
            let g = run_one(k, seed);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(n, jobs.len());
            g
        })
        .collect()
}

/// Calibration figures of a set of grades.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Calibration {
    pub missions: usize,
    /// Missions whose Δt was applied (status ok).
    pub applied: usize,
    /// |error| percentiles (50, 90, 100), seconds.
    pub error_p50_s: f64,
    pub error_p90_s: f64,
    pub error_max_s: f64,
    /// Share of applied missions with |error| ≤ 2σ.
    pub coverage_2sigma: f64,
    /// Median of |error|/σ.
    pub median_error_over_sigma: f64,
    /// Missions with σ > 50 ms although |error| < 10 ms.
    pub sigma_too_large: usize,
    /// The same over every profile window.
    pub windows: usize,
    pub window_coverage_2sigma: f64,
    pub window_median_error_over_sigma: f64,
    pub window_sigma_too_large: usize,
    /// Drift or step warnings.
    pub clock_alarms: usize,
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i]
}

/// The calibration figures of `grades`.
pub fn calibration(grades: &[&MissionGrade]) -> Calibration {
    let applied: Vec<(f64, f64)> = grades
        .iter()
        .filter_map(|g| Some((g.error_s?, g.sigma_s?)))
        .collect();
    let mut abs: Vec<f64> = applied.iter().map(|e| e.0.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let ratio = |v: &[(f64, f64)]| {
        let mut r: Vec<f64> = v.iter().map(|(e, s)| e.abs() / s).collect();
        r.sort_by(f64::total_cmp);
        percentile(&r, 0.5)
    };
    let cover = |v: &[(f64, f64)]| {
        v.iter().filter(|(e, s)| e.abs() <= 2.0 * s).count() as f64 / v.len().max(1) as f64
    };
    let too_large = |v: &[(f64, f64)]| {
        v.iter()
            .filter(|(e, s)| *s > 0.05 && e.abs() < 0.01)
            .count()
    };
    let w: Vec<(f64, f64)> = grades
        .iter()
        .filter(|g| g.status == Some(TimeOffsetStatus::Ok))
        .flat_map(|g| g.windows.iter().map(|w| (w.error_s, w.sigma_s)))
        .collect();
    Calibration {
        missions: grades.len(),
        applied: applied.len(),
        error_p50_s: percentile(&abs, 0.5),
        error_p90_s: percentile(&abs, 0.9),
        error_max_s: abs.last().copied().unwrap_or(f64::NAN),
        coverage_2sigma: cover(&applied),
        median_error_over_sigma: ratio(&applied),
        sigma_too_large: too_large(&applied),
        windows: w.len(),
        window_coverage_2sigma: cover(&w),
        window_median_error_over_sigma: ratio(&w),
        window_sigma_too_large: too_large(&w),
        clock_alarms: grades.iter().filter(|g| g.clock_alarm).count(),
    }
}

/// The calibration table (Markdown) of `grades`: one row per kind, one for every constant-clock
/// mission, then the drift and step recovery.
pub fn table(grades: &[MissionGrade]) -> String {
    let mut out = String::new();
    calibration_rows(&mut out, grades);
    drift_rows(&mut out, grades);
    step_rows(&mut out, grades);
    out
}

/// Seconds as milliseconds, one decimal.
fn ms(t_s: f64) -> String {
    format!("{:.1}", t_s * 1e3)
}

/// The calibration table's header and rows: one per kind (in the grades' order), then every
/// constant-clock mission (when the kinds mix clocks) and the legged ones among them.
fn calibration_rows(out: &mut String, grades: &[MissionGrade]) {
    use std::fmt::Write;
    let _ = writeln!(
        out,
        "| kind | missions | applied | |error| p50 / p90 / max ms | 2σ covers | median |error|/σ | σ > 50 ms at |error| < 10 ms: missions / windows | windows: 2σ covers | median |error|/σ | clock alarms |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|");
    let mut kinds: Vec<&str> = Vec::new();
    for g in grades {
        if !kinds.contains(&g.kind.as_str()) {
            kinds.push(&g.kind);
        }
    }
    for k in &kinds {
        let set: Vec<&MissionGrade> = grades.iter().filter(|g| g.kind == *k).collect();
        calibration_row(out, k, &set);
    }
    let constant: Vec<&MissionGrade> = grades
        .iter()
        .filter(|g| {
            g.kind
                .parse::<MissionKind>()
                .map_or(true, MissionKind::constant_clock)
        })
        .collect();
    if constant.len() < grades.len() && !constant.is_empty() {
        calibration_row(out, "**all constant clocks**", &constant);
    }
    let legged: Vec<&MissionGrade> = constant.iter().copied().filter(|g| g.legged).collect();
    if !legged.is_empty() {
        calibration_row(out, "**legged, constant clocks**", &legged);
    }
}

/// One row of the calibration table: the [`calibration`] of `set`, named `name`.
fn calibration_row(out: &mut String, name: &str, set: &[&MissionGrade]) {
    use std::fmt::Write;
    let c = calibration(set);
    let _ = writeln!(
        out,
        "| {name} | {} | {} | {} / {} / {} | {:.0} % | {:.2} | {} / {} | {:.0} % of {} | {:.2} | {} |",
        c.missions,
        c.applied,
        ms(c.error_p50_s),
        ms(c.error_p90_s),
        ms(c.error_max_s),
        c.coverage_2sigma * 100.0,
        c.median_error_over_sigma,
        c.sigma_too_large,
        c.window_sigma_too_large,
        c.window_coverage_2sigma * 100.0,
        c.windows,
        c.window_median_error_over_sigma,
        c.clock_alarms
    );
}

/// The drift recovery table: one row per mission whose clock drifts (nothing when none does).
fn drift_rows(out: &mut String, grades: &[MissionGrade]) {
    use std::fmt::Write;
    let drifting: Vec<&MissionGrade> = grades.iter().filter(|g| g.drift_true_ppm != 0.0).collect();
    if drifting.is_empty() {
        return;
    }
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "| drift: kind, seed | platform | true ppm | model | drift ppm ± σ (error) | resolution ppm | σ ms | truth's spread about Δt ms |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|");
    for g in &drifting {
        let _ = writeln!(
            out,
            "| {} {} | {} | {:+.0} | {} | {} | {} | {} | {:.1} |",
            g.kind,
            g.seed,
            if g.legged { "legged" } else { "ground" },
            g.drift_true_ppm,
            g.model.map_or("-", |m| m.as_str()),
            g.drift_ppm.map_or("-".into(), |d| format!(
                "{d:+.1} ± {} ({:+.1})",
                g.drift_sigma_ppm.map_or("-".into(), |s| format!("{s:.1}")),
                d - g.drift_true_ppm
            )),
            g.drift_resolution_ppm
                .map_or("-".into(), |r| format!("{r:.1}")),
            g.sigma_s.map_or("-".into(), ms),
            g.spread_s * 1e3
        );
    }
    let c = drift_calibration(&drifting);
    if c.declared > 0 {
        let _ = writeln!(
            out,
            "\nDeclared drifts: {} of {}; 2σ covers the drift's error on {:.0} %, median |error|/σ {:.2}.",
            c.declared,
            drifting.len(),
            c.coverage_2sigma * 100.0,
            c.median_error_over_sigma
        );
    }
}

/// How well the declared drifts' σ describe their errors.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DriftCalibration {
    /// Missions whose model is `linear` (a drift applied) with a σ.
    pub declared: usize,
    /// Share of them whose |drift − truth| ≤ 2σ.
    pub coverage_2sigma: f64,
    /// Median of |drift − truth|/σ.
    pub median_error_over_sigma: f64,
}

/// The [`DriftCalibration`] of `grades` (those without a declared drift are skipped).
pub fn drift_calibration(grades: &[&MissionGrade]) -> DriftCalibration {
    let mut r: Vec<f64> = grades
        .iter()
        .filter_map(|g| {
            let (d, s) = (g.drift_ppm?, g.drift_sigma_ppm?);
            (s > 0.0).then(|| (d - g.drift_true_ppm).abs() / s)
        })
        .collect();
    r.sort_by(f64::total_cmp);
    DriftCalibration {
        declared: r.len(),
        coverage_2sigma: r.iter().filter(|&&x| x <= 2.0).count() as f64 / r.len().max(1) as f64,
        median_error_over_sigma: percentile(&r, 0.5),
    }
}

/// The step recovery table: one row per step mission (nothing when there is none).
fn step_rows(out: &mut String, grades: &[MissionGrade]) {
    use std::fmt::Write;
    let steps: Vec<&MissionGrade> = grades.iter().filter(|g| g.kind == "step").collect();
    if steps.is_empty() {
        return;
    }
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "| step: seed | platform | model | change located (s off) | worst segment error ms |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|");
    for g in steps {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} |",
            g.seed,
            if g.legged { "legged" } else { "ground" },
            g.model.map_or("-", |m| m.as_str()),
            g.step_time_error_s
                .map_or("-".into(), |e| format!("{e:+.1}")),
            g.step_segment_error_s.map_or("-".into(), ms)
        );
    }
}

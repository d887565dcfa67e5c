//! `trajdrift audit`: the clock map of a whole mission, and `trajdrift restamp`: a copy with its
//! clocks fixed.
//!
//! A curated dataset needs, per source, which clock it is on (offset, drifting, stepping), where its
//! sensor sits relative to the others, and which sources disagree. The audit answers it from one
//! streaming pass over every file of the mission ([`crate::eval::inputs::load`] reads every source at
//! once), then evaluates every pair of sources on the loaded trajectories with the evaluation itself
//! ([`pairs`]: the offset search, σ, clock model — so the audit gets whatever the evaluation knows),
//! and builds on those results:
//!
//! - [`discover`](mod@discover): which topics are sources, which is the reference, which file each came from;
//! - [`pairs`]: the offset of every overlapping pair, [`chain`]: measured through the reference's
//!   clock;
//! - [`coverage`]: rate, gaps and coverage of each source;
//! - [`lever`]: each source's lever arm (the evaluation's pose fit from its orientation, or lateral
//!   and forward from positions);
//! - [`closure`]: Δt_AB + Δt_BC − Δt_AC of every triple with its σ and a χ² test, naming a source
//!   out of line;
//! - [`domains`]: sources grouped by clock;
//! - [`judge`]: closure, the source (or pair) out of line and the domains, from the pairs' clocks —
//!   also on an audit read back and edited (`judge::rejudge`);
//! - [`report`]: the result and its JSON (`schemas/audit.schema.json`), [`table`] and [`html`] its text
//!   and page;
//! - [`restamp_plan`] and [`restamp`]: which messages move by which clock, and the copy that moves them.
//!
//! Layering: above `eval`, `annotate` (the copier `restamp` reuses), `plot` and `render`; below `batch`.

pub mod chain;
pub mod closure;
pub mod coverage;
pub mod discover;
pub mod domains;
pub mod html;
pub mod judge;
pub mod lever;
pub mod pairs;
pub mod report;
pub mod restamp;
pub mod restamp_plan;
pub mod table;

use std::path::PathBuf;

use crate::clock::ClockCorrection;
use crate::diag::{Warning, WarningCode};
use crate::error::{Error, Result};
use crate::eval::config::EvalConfig;
use crate::eval::inputs::{load, Loaded};
use crate::eval::parameters::Parameters;
use crate::report::json::{EstimateReport, Report, TimeOffsetStatus, Tool};
use crate::sources::Progress;
use crate::trajectory::Trajectory;
use discover::{discover, Discovered, SourceRequest};
use report::{
    AuditReport, Clock, OutOfLine, OutOfLineReason, PairMeasurement, PairOffset, SourceAudit,
    AUDIT_KIND, AUDIT_SCHEMA_VERSION,
};

/// What to audit.
#[derive(Debug, Clone, Default)]
pub struct AuditConfig {
    /// The recording: one file, several files of one mission, or a mission folder.
    pub recordings: Vec<PathBuf>,
    pub request: SourceRequest,
    /// Evaluation parameters (every pair is evaluated with them).
    pub params: Parameters,
}

/// An audit and what the user should know about how it was made.
#[derive(Debug, Clone)]
pub struct AuditOutcome {
    pub report: AuditReport,
    /// What the user should know about choices made (the reference picked, …).
    pub notes: Vec<String>,
}

/// The evaluation's request for every source at once (one pass), keeping orientations (the pose
/// fit and the lever's tilt test read them).
fn eval_config(config: &AuditConfig, d: &Discovered) -> EvalConfig {
    let mut c = EvalConfig::new(
        config.recordings.first().cloned(),
        d.reference.clone(),
        d.sources.clone(),
    );
    c.more_recordings = config.recordings.iter().skip(1).cloned().collect();
    c.params = config.params.clone();
    c.keep_orientations = true;
    c
}

/// `--t-start`/`--t-end` below 1e8 count from the reference's first sample: made absolute here, since
/// each pair is evaluated against its own first source.
fn absolute_crop(params: &mut Parameters, reference: &Trajectory) {
    let t0 = reference.stamps_ns.first().copied().unwrap_or(0) as f64 * 1e-9;
    for v in [&mut params.t_start, &mut params.t_end]
        .into_iter()
        .flatten()
    {
        if v.abs() < 1e8 {
            *v += t0;
        }
    }
}

/// Runs the audit.
pub fn audit(config: &AuditConfig, progress: Progress<'_>) -> Result<AuditOutcome> {
    let found = discover(&config.recordings, &config.request)?;
    let mut eval = eval_config(config, &found);
    eval.validate()?;
    let inputs = load(&eval, progress)?;
    let read_warnings = inputs.warnings.clone();
    let mut sources: Vec<Loaded> = Vec::with_capacity(inputs.estimates.len() + 1);
    sources.push(inputs.reference);
    sources.extend(inputs.estimates);
    absolute_crop(&mut eval.params, &sources[0].trajectory);
    // The reference's pairs first: every other pair is measured on their clocks; each source's
    // lever is the one its pair with the reference fitted.
    let mut evaluations = pairs::reference_pairs(&eval, &sources);
    let clocks = reference_clocks(&sources, &evaluations, span_s(&sources[0].trajectory));
    let levers = levers(&sources, &evaluations, &clocks);
    evaluations.extend(pairs::other_pairs(&eval, &sources, &evaluations));
    let measured = Measured {
        evaluations,
        clocks,
        levers,
    };
    let report = build(config, &found, &sources, &measured, read_warnings)?;
    Ok(AuditOutcome {
        report,
        notes: found.notes,
    })
}

/// The evaluation report of every source against the reference, merged from the reference's pairs.
fn merged_evaluation(
    sources: &[Loaded],
    evaluations: &[pairs::PairEvaluation],
    warnings: &[Warning],
) -> Result<Report> {
    let mut template: Option<Report> = None;
    let mut estimates = Vec::new();
    let mut all_warnings = warnings.to_vec();
    let mut first_error = None;
    for e in evaluations.iter().filter(|e| e.a == 0) {
        match &e.result {
            Ok((est, report)) => {
                estimates.push(est.clone());
                all_warnings.extend(report.warnings.iter().cloned());
                template.get_or_insert_with(|| report.clone());
            }
            Err(msg) => {
                first_error.get_or_insert_with(|| format!("{}: {msg}", sources[e.b].name));
            }
        }
    }
    let Some(mut report) = template else {
        return Err(Error::InvalidArgument(format!(
            "no source could be evaluated against the reference {}: {}",
            sources[0].label,
            first_error.unwrap_or_default()
        )));
    };
    report.estimates = estimates;
    report.warnings = all_warnings;
    Ok(report)
}

/// The span of a trajectory, absolute seconds on its own clock.
fn span_s(t: &Trajectory) -> (f64, f64) {
    t.span_ns()
        .map_or((0.0, 0.0), |(a, b)| (a as f64 * 1e-9, b as f64 * 1e-9))
}

/// The report of pair (a, b), when it was evaluated.
fn pair_report(
    evaluations: &[pairs::PairEvaluation],
    a: usize,
    b: usize,
) -> Option<&EstimateReport> {
    evaluations
        .iter()
        .find(|e| e.a == a && e.b == b)
        .and_then(|e| e.result.as_ref().ok().map(|(r, _)| r))
}

/// Each source's clock against the reference (the reference's own first), with the span it covers on
/// the reference clock.
fn reference_clocks(
    sources: &[Loaded],
    evaluations: &[pairs::PairEvaluation],
    reference_span: (f64, f64),
) -> Vec<Option<Clock>> {
    let mut clocks = vec![Some(Clock::reference(reference_span.0, reference_span.1))];
    for (b, source) in sources.iter().enumerate().skip(1) {
        clocks.push(pair_report(evaluations, 0, b).map(|r| {
            let c = ClockCorrection::from_report(&r.time_offset);
            let cov = coverage::coverage(&source.trajectory, &c, reference_span);
            Clock::from_time_offset(
                &r.time_offset,
                (
                    cov.t_start.max(reference_span.0),
                    cov.t_end.min(reference_span.1),
                ),
            )
        }));
    }
    clocks
}

/// Every measured pair, as listed and as a matrix (`[a][b]`, a < b).
fn pair_offsets(
    sources: &[Loaded],
    evaluations: &[pairs::PairEvaluation],
    clocks: &[Option<Clock>],
) -> (Vec<PairOffset>, Vec<Vec<Option<Clock>>>) {
    let n = sources.len();
    let mut pair_list = Vec::new();
    let mut pair_clock: Vec<Vec<Option<Clock>>> = vec![vec![None; n]; n];
    for e in evaluations {
        let Ok((r, _)) = &e.result else { continue };
        let (sa, sb) = (
            span_s(&sources[e.a].trajectory),
            span_s(&sources[e.b].trajectory),
        );
        let span = (sa.0.max(sb.0), sa.1.min(sb.1));
        let measured = Clock::from_time_offset(&r.time_offset, span);
        let clock = match (e.a, &clocks[e.a], &clocks[e.b], e.measured) {
            (0, _, Some(c), _) => c.clone(),
            (_, Some(ca), Some(cb), PairMeasurement::ThroughReference) => {
                match chain::chained(ca, cb, &measured, span) {
                    Some(c) => c,
                    None => continue,
                }
            }
            _ => measured,
        };
        pair_clock[e.a][e.b] = Some(clock.clone());
        pair_list.push(PairOffset {
            a: sources[e.a].name.clone(),
            b: sources[e.b].name.clone(),
            clock,
            overlap_s: e.overlap_s,
            measured: e.measured,
        });
    }
    (pair_list, pair_clock)
}

/// A clock against the reference, in words: its model and its drift or segments.
fn clock_words(c: &Clock) -> String {
    match c.model {
        crate::align::clock_model::OffsetModel::Linear => {
            format!("{:+.1} ppm", c.drift_ppm.unwrap_or(f64::NAN))
        }
        _ => c
            .segments
            .iter()
            .map(|s| format!("{:+.4} s", s.offset_s))
            .collect::<Vec<_>>()
            .join(" → "),
    }
}

/// The sources whose clock against the reference is weak, not constant or missing, and the
/// warnings of the missing ones.
fn clock_findings(
    sources: &[Loaded],
    clocks: &[Option<Clock>],
    evaluations: &[pairs::PairEvaluation],
) -> (Vec<OutOfLine>, Vec<Warning>) {
    let mut out_of_line = Vec::new();
    let mut warnings = Vec::new();
    let line = |name: &String, reason, detail: String| OutOfLine {
        source: name.clone(),
        reason,
        detail,
    };
    for (b, source) in sources.iter().enumerate().skip(1) {
        let name = &source.name;
        match &clocks[b] {
            Some(c) if c.status == TimeOffsetStatus::Weak => out_of_line.push(line(
                name,
                OutOfLineReason::WeakOffset,
                format!("{name}: no confident offset against the reference"),
            )),
            Some(c) if !c.is_constant() => out_of_line.push(line(
                name,
                OutOfLineReason::ClockNotConstant,
                format!(
                    "{name}: {} clock against the reference ({})",
                    c.model.as_str(),
                    clock_words(c)
                ),
            )),
            Some(_) => {}
            None => {
                let why = evaluations
                    .iter()
                    .find(|e| e.a == 0 && e.b == b)
                    .and_then(|e| e.result.as_ref().err().cloned())
                    .unwrap_or_default();
                let detail = format!("{name}: not evaluated against the reference: {why}");
                warnings.push(Warning::new(WarningCode::WeakTimeOffset, detail.clone()));
                out_of_line.push(line(name, OutOfLineReason::WeakOffset, detail));
            }
        }
    }
    (out_of_line, warnings)
}

/// A source's lever arm: the evaluation's pose fit where the source has orientation and a confident
/// clock, else lateral and forward from positions; none for the reference or an unevaluated one.
fn lever_of(
    source: &Loaded,
    clock: &Clock,
    est: Option<&EstimateReport>,
) -> Option<report::LeverFit> {
    let e = est?;
    let pose = match (&source.trajectory.orientations, clock.status) {
        (Some(_), TimeOffsetStatus::Ok) => lever::pose_lever(&e.time_offset, &source.trajectory),
        _ => None,
    };
    Some(pose.unwrap_or_else(|| lever::positions_lever(e)))
}

/// Every source's lever arm (none for the reference).
fn levers(
    sources: &[Loaded],
    evaluations: &[pairs::PairEvaluation],
    clocks: &[Option<Clock>],
) -> Vec<Option<report::LeverFit>> {
    (0..sources.len())
        .map(|i| {
            let clock = clocks[i].as_ref()?;
            let est = (i > 0).then(|| pair_report(evaluations, 0, i)).flatten();
            lever_of(&sources[i], clock, est)
        })
        .collect()
}

/// What the audit measured: every pair's evaluation, each source's clock against the reference
/// (`None` where it has none) and its lever.
struct Measured {
    evaluations: Vec<pairs::PairEvaluation>,
    clocks: Vec<Option<Clock>>,
    levers: Vec<Option<report::LeverFit>>,
}

/// Source `i`'s line of the audit.
fn source_audit(
    i: usize,
    sources: &[Loaded],
    found: &Discovered,
    measured: &Measured,
    domain: String,
) -> SourceAudit {
    let s = &sources[i];
    let reference_span = span_s(&sources[0].trajectory);
    let est = (i > 0)
        .then(|| pair_report(&measured.evaluations, 0, i))
        .flatten();
    let clock = measured.clocks[i]
        .clone()
        .unwrap_or_else(|| Clock::reference(f64::NAN, f64::NAN));
    let correction = if i == 0 {
        ClockCorrection::Constant { dt_ns: 0 }
    } else {
        clock.correction()
    };
    let lever = if i == 0 {
        None
    } else {
        measured.levers[i].clone()
    };
    let de = est.and_then(|e| e.drift_error.first());
    SourceAudit {
        name: s.name.clone(),
        topic: s.label.clone(),
        type_name: s.type_name.clone(),
        file: found.file_of(&s.label).map(|p| p.display().to_string()),
        reference: i == 0,
        samples: s.trajectory.len(),
        rate_hz: s
            .trajectory
            .median_period_s()
            .filter(|p| *p > 0.0)
            .map(|p| 1.0 / p),
        gaps: coverage::gaps(&s.trajectory),
        coverage: coverage::coverage(&s.trajectory, &correction, reference_span),
        clock,
        lever_m: if i == 0 {
            Some([Some(0.0); 3])
        } else {
            lever.as_ref().map(|l| l.lever_m)
        },
        lever,
        de_rmse: de.and_then(|d| d.rmse),
        de_window_m: de.map(|d| d.window_m),
        ape_rmse_m: est
            .and_then(|e| e.standard_metrics.as_ref())
            .and_then(|m| m.ape.as_ref())
            .map(|a| a.stats.rmse),
        domain,
    }
}

fn build(
    config: &AuditConfig,
    found: &Discovered,
    sources: &[Loaded],
    measured: &Measured,
    read_warnings: Vec<Warning>,
) -> Result<AuditReport> {
    let (evaluations, clocks) = (&measured.evaluations, &measured.clocks);
    let evaluation = merged_evaluation(sources, evaluations, &read_warnings)?;
    let reference_span = span_s(&sources[0].trajectory);
    let (pair_list, pair_clock) = pair_offsets(sources, evaluations, clocks);
    let pair = |a: usize, b: usize| pair_clock[a.min(b)][a.max(b)].clone();
    let names: Vec<String> = sources.iter().map(|s| s.name.clone()).collect();
    let spans: Vec<(f64, f64)> = sources.iter().map(|s| span_s(&s.trajectory)).collect();
    let judged = judge::judge(&names, &spans, &pair, reference_span);
    // The evaluation's lever warnings are the audit's lever report's business.
    let mut warnings: Vec<Warning> = evaluation
        .warnings
        .iter()
        .filter(|w| !w.code.is_lever())
        .cloned()
        .collect();
    let (mut out_of_line, missing) = clock_findings(sources, clocks, evaluations);
    warnings.extend(missing);
    out_of_line.extend(judged.out_of_line);
    warnings.extend(judged.warning);
    let source_list = (0..sources.len())
        .map(|i| source_audit(i, sources, found, measured, judged.domain_of[i].clone()))
        .collect();
    Ok(AuditReport {
        kind: AUDIT_KIND.into(),
        schema_version: AUDIT_SCHEMA_VERSION,
        tool: Tool::default(),
        inputs: config
            .recordings
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
        files: found
            .files
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
        reference: sources[0].name.clone(),
        stamp: config.params.stamp(),
        sources: source_list,
        pairs: pair_list,
        closure: judged.closure,
        domains: judged.domains,
        out_of_line,
        warnings,
        evaluation,
    })
}

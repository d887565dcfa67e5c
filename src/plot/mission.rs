//! Builds a mission's figures from its report and the trajectories it was computed from (the
//! reference as cropped, the estimates before their time shift).

use nalgebra::Vector3;

use super::drift_error::{DeSeries, DriftAlong};
use super::offset_curves::{correlation_curve, CorrelationCurve};
use super::offset_profile::OffsetProfile;
use super::offset_search::OffsetSearch;
use super::speed::SpeedFit;
use super::top_view::TopView;
use super::{Figure, FigureData, Trajectories};
use crate::align::auto_params::reference_noise;
use crate::align::curvature::CurvatureParams;
use crate::align::speed::speed_profile;
use crate::align::time_offset::{OffsetMethod, OffsetParams};
use crate::clock::ClockCorrection;
use crate::output::names::file_stem;
use crate::report::json::{DriftErrorReport, EstimateReport, Parameters, Report, TimeOffsetStatus};
use crate::trajectory::Trajectory;

/// Half-width of the lag range drawn around the answer, at least, seconds.
const MIN_HALF_WIDTH_S: f64 = 5.0;

/// Every figure of every estimate of `report`, in a stable order.
pub fn mission_figures(report: &Report, inputs: &Trajectories<'_>) -> Vec<Figure> {
    let reference = inputs.reference;
    let t0_ns = reference.stamps_ns.first().copied().unwrap_or(0);
    let mut out = Vec::new();
    for e in &report.estimates {
        let Some(&(_, est)) = inputs.estimates.iter().find(|(name, _)| *name == e.name) else {
            continue;
        };
        let aligned = aligned(est, e, &report.parameters);
        let stem = file_stem(&e.name);
        let fig = |kind: &str, title: String, data: FigureData| Figure {
            name: format!("{stem}_{kind}"),
            title,
            data,
        };
        if let Some(d) = e.drift_error.first() {
            let t = format!(
                "Top view: reference and aligned {} coloured by Drift Error",
                e.name
            );
            out.push(fig(
                "top_view",
                t.clone(),
                FigureData::TopView(top_view(t, reference, &aligned, d)),
            ));
        }
        let t = format!("Drift Error of {} along the reference path", e.name);
        out.push(fig(
            "drift_error",
            t.clone(),
            FigureData::DriftAlong(drift_along(
                t,
                reference,
                &e.drift_error,
                report.parameters.path_eps_m,
            )),
        ));
        if !e.time_offset.methods.is_empty() {
            let t = format!("Time-offset search of {}: correlation against Δt", e.name);
            let data = offset_search(t.clone(), reference, est, e, &report.parameters, t0_ns);
            out.push(fig("offset_search", t, FigureData::OffsetSearch(data)));
        }
        let ref_t = reference.times_s(t0_ns);
        let t = format!("Time offset of {} over the mission", e.name);
        let profile = OffsetProfile::from_report(
            t.clone(),
            &e.time_offset,
            t0_ns as f64 * 1e-9,
            (0.0, ref_t.last().copied().unwrap_or(0.0)),
        );
        out.push(fig("offset_profile", t, FigureData::OffsetProfile(profile)));
        let t = format!("Speed of the reference and of aligned {}", e.name);
        let data = speed_fit(t.clone(), reference, &aligned, &report.parameters, t0_ns);
        out.push(fig("speed", t, FigureData::Speed(data)));
    }
    out
}

/// The estimate on the reference clock as the evaluation moved it (its clock model, to the
/// nanosecond), cropped like the evaluation.
fn aligned(est: &Trajectory, e: &EstimateReport, p: &Parameters) -> Trajectory {
    let mut a = ClockCorrection::from_report(&e.time_offset).apply(est);
    let ns = |s: Option<f64>| s.map(|s| (s * 1e9).round() as i64);
    a.crop(ns(p.t_start), ns(p.t_end));
    a
}

fn abs_s(ns: i64) -> f64 {
    ns as f64 * 1e-9
}

fn top_view(
    title: String,
    reference: &Trajectory,
    aligned: &Trajectory,
    d: &DriftErrorReport,
) -> TopView {
    let in_window = |t: f64| -> Option<f64> {
        // Windows are in time order; the first one whose start is after t ends the search.
        let i = d.per_window.partition_point(|w| w.t_start <= t);
        d.per_window[..i]
            .iter()
            .rev()
            .take(4)
            .find(|w| t <= w.t_end)
            .map(|w| w.de)
    };
    let excluded = |t: f64| {
        d.excluded_intervals
            .iter()
            .any(|iv| t >= iv[0] && t <= iv[1])
    };
    let mut v = TopView {
        title,
        window_m: d.window_m,
        reference: reference.positions.iter().map(|p| (p.x, p.y)).collect(),
        ..Default::default()
    };
    let fit = display_fit(reference, aligned);
    for (ns, p) in aligned.stamps_ns.iter().zip(&aligned.positions) {
        let t = abs_s(*ns);
        let (x, y) = fit(p);
        v.estimate.push((x, y, in_window(t)));
        if excluded(t) {
            v.excluded.push((x, y));
        }
    }
    v
}

/// The rotation about z and translation that best lay the estimate (its own frame) onto the
/// reference at the same times (2-D Kabsch, least squares) — for display only: Drift Error needs no
/// spatial alignment, but a reader compares shapes best when they overlap.
fn display_fit(
    reference: &Trajectory,
    aligned: &Trajectory,
) -> impl Fn(&Vector3<f64>) -> (f64, f64) {
    let r = reference;
    let pairs: Vec<((f64, f64), (f64, f64))> = super::style::decimate(aligned.len(), 5000)
        .into_iter()
        .filter_map(|i| {
            let t = aligned.stamps_ns[i];
            let j = r.stamps_ns.partition_point(|&x| x < t);
            let k = [j.saturating_sub(1), j]
                .into_iter()
                .filter(|&k| k < r.len())
                .min_by_key(|&k| (r.stamps_ns[k] - t).abs())?;
            // Pairs further apart in time than 0.5 s (a gap in the reference) are left out.
            ((r.stamps_ns[k] - t).abs() < 500_000_000).then(|| {
                let (e, q) = (aligned.positions[i], r.positions[k]);
                ((e.x, e.y), (q.x, q.y))
            })
        })
        .collect();
    let n = pairs.len().max(1) as f64;
    let (mut ce, mut cr) = ((0.0, 0.0), (0.0, 0.0));
    for ((ex, ey), (rx, ry)) in &pairs {
        ce = (ce.0 + ex / n, ce.1 + ey / n);
        cr = (cr.0 + rx / n, cr.1 + ry / n);
    }
    // The optimal angle of a 2-D rotation: atan2 of the cross and dot sums of the centred pairs.
    let (mut cross, mut dot) = (0.0, 0.0);
    for ((ex, ey), (rx, ry)) in &pairs {
        let (a, b) = ((ex - ce.0, ey - ce.1), (rx - cr.0, ry - cr.1));
        cross += a.0 * b.1 - a.1 * b.0;
        dot += a.0 * b.0 + a.1 * b.1;
    }
    let th = if pairs.len() >= 3 {
        cross.atan2(dot)
    } else {
        0.0
    };
    let (c, s) = (th.cos(), th.sin());
    let (ce, cr) = if pairs.len() >= 3 {
        (ce, cr)
    } else {
        ((0.0, 0.0), (0.0, 0.0))
    };
    move |p: &Vector3<f64>| {
        let (x, y) = (p.x - ce.0, p.y - ce.1);
        (c * x - s * y + cr.0, s * x + c * y + cr.1)
    }
}

/// Distance along the reference (ε-decimated, so noise does not inflate it) at each sample.
fn cumulative_distance(positions: &[Vector3<f64>], eps: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(positions.len());
    let (mut d, mut last) = (0.0, positions.first().copied());
    for p in positions {
        if let Some(l) = last {
            let step = (p - l).norm();
            if step >= eps {
                d += step;
                last = Some(*p);
            }
        }
        out.push(d);
    }
    out
}

fn drift_along(
    title: String,
    reference: &Trajectory,
    des: &[DriftErrorReport],
    eps: f64,
) -> DriftAlong {
    let times: Vec<f64> = reference.stamps_ns.iter().map(|&n| abs_s(n)).collect();
    let dist = cumulative_distance(&reference.positions, eps.max(1e-6));
    let at = |t: f64| {
        dist[times
            .partition_point(|&x| x < t)
            .min(dist.len().saturating_sub(1))]
    };
    let series = des
        .iter()
        .map(|d| DeSeries {
            window_m: d.window_m,
            points: d
                .per_window
                .iter()
                .map(|w| (at(0.5 * (w.t_start + w.t_end)), w.de))
                .collect(),
            median: d.median,
            q1: d.q1,
            q3: d.q3,
        })
        .collect();
    DriftAlong { title, series }
}

/// The search's parameters as the report states them.
pub fn offset_params(p: &Parameters) -> OffsetParams {
    OffsetParams {
        max_offset_s: p.max_offset_s,
        grid_s: p.grid_s,
        curvature: CurvatureParams {
            eps_m: p.curvature_eps_m,
            theta_max_rad: p.theta_max_rad,
            dt_max_s: p.curvature_dt_max_s.unwrap_or(p.dt_max_s),
        },
        max_gap_s: Some(p.dt_max_s),
        ..OffsetParams::default()
    }
}

fn offset_search(
    title: String,
    reference: &Trajectory,
    est: &Trajectory,
    e: &EstimateReport,
    p: &Parameters,
    t0_ns: i64,
) -> OffsetSearch {
    let params = offset_params(p);
    let ref_t = reference.times_s(t0_ns);
    let est_t = est.times_s(t0_ns);
    let peaks: Vec<f64> = e
        .time_offset
        .methods
        .iter()
        .filter_map(|m| m.offset_s)
        .collect();
    let center = e.time_offset.offset_s;
    let spread = peaks.iter().map(|x| (x - center).abs()).fold(0.0, f64::max);
    let half = (spread + 2.0).max(MIN_HALF_WIDTH_S).min(p.max_offset_s);
    let curves = e
        .time_offset
        .methods
        .iter()
        .filter(|m| m.method != OffsetMethod::Auto)
        .map(|m| CorrelationCurve {
            method: m.method,
            points: correlation_curve(
                m.method,
                &ref_t,
                &reference.positions,
                &est_t,
                &est.positions,
                &params,
                center,
                half,
            ),
            peak: m.offset_s.zip(m.correlation),
        })
        .collect();
    OffsetSearch {
        title,
        curves,
        chosen_s: (e.time_offset.status == TimeOffsetStatus::Ok).then_some(e.time_offset.applied_s),
    }
}

fn speed_fit(
    title: String,
    reference: &Trajectory,
    aligned: &Trajectory,
    p: &Parameters,
    t0_ns: i64,
) -> SpeedFit {
    let window_s = OffsetParams::default().speed_window_s;
    let profile = |t: &[f64], pos: &[Vector3<f64>]| -> Vec<(f64, f64)> {
        let noise = reference_noise(t, pos).unwrap_or(0.0);
        speed_profile(t, pos, window_s, p.dt_max_s, noise)
            .into_iter()
            .map(|s| (s.t, s.speed))
            .collect()
    };
    let reference_t = reference.times_s(t0_ns);
    // Thinning to MAX_POINTS spaces the points by span/MAX_POINTS; a gap must be longer than that.
    let span =
        reference_t.last().copied().unwrap_or(0.0) - reference_t.first().copied().unwrap_or(0.0);
    SpeedFit {
        title,
        max_gap_s: p.dt_max_s.max(3.0 * span / super::style::MAX_POINTS as f64),
        reference: profile(&reference.times_s(t0_ns), &reference.positions),
        estimate: profile(&aligned.times_s(t0_ns), &aligned.positions),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::align::clock_model::OffsetModel;
    use crate::eval::config::{EvalConfig, NamedInput};
    use crate::plot::FigureData;

    /// The shared evidence (`$TRAJDRIFT_SHARED`, default `../shared`); `None` outside CI when it is
    /// missing, a failure under CI.
    fn shared() -> Option<std::path::PathBuf> {
        let explicit = std::env::var("TRAJDRIFT_SHARED").ok();
        let dir = explicit
            .clone()
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|| {
                std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared")
            });
        if dir.join("fixtures").is_dir() {
            return Some(dir);
        }
        assert!(
            explicit.is_none() && std::env::var_os("CI").is_none(),
            "shared data missing at {} (TRAJDRIFT_SHARED); CI must have it",
            dir.display()
        );
        None
    }

    /// The times of the aligned estimate's speed series in the mission's figures.
    fn speed_figure_times(report: &Report, inputs: &crate::eval::inputs::Inputs) -> Vec<f64> {
        let estimates = inputs.named_estimates();
        let figures = mission_figures(
            report,
            &Trajectories {
                reference: &inputs.reference.trajectory,
                estimates: &estimates,
            },
        );
        figures
            .iter()
            .find_map(|f| match &f.data {
                FigureData::Speed(s) => Some(s.estimate.iter().map(|p| p.0).collect()),
                _ => None,
            })
            .expect("a speed figure")
    }

    /// Under a piecewise model (the shared `clock_step` mission, whose clock steps by −0.5 s at
    /// 200 s) the figures move the estimate by the model, not by the headline constant.
    #[test]
    fn figures_follow_a_piecewise_clock_model() {
        let Some(shared) = shared() else {
            return;
        };
        let dir = shared.join("fixtures/clock_step");
        let c = EvalConfig::new(
            Some(dir.join("mission.mcap")),
            NamedInput::topic("/reference/position"),
            vec![NamedInput::topic("/estimate/odom")],
        );
        let (report, inputs) = crate::eval::evaluate_with_inputs(&c, &|_| {}).unwrap();
        let o = &report.estimates[0].time_offset;
        assert_eq!(o.model, Some(OffsetModel::Piecewise), "{o:?}");
        let first_segment = o.segments[0].offset_s;
        // The same report with its model taken away: the figures then shift by the constant.
        let mut constant = report.clone();
        constant.estimates[0].time_offset.model = Some(OffsetModel::Constant);
        let (piecewise, shifted) = (
            speed_figure_times(&report, &inputs),
            speed_figure_times(&constant, &inputs),
        );
        // The mission starts in the first segment: its offset, not the headline's, moved it. One of
        // the constant's first samples is among the model's first few, that much later (either's
        // first sample may be one the other leaves outside the reference's span).
        let expected = first_segment - o.applied_s;
        assert!(
            piecewise.iter().take(3).any(|&t| shifted
                .iter()
                .take(3)
                .any(|&c| (t - (c + expected)).abs() < 1e-6)),
            "expected a move of {expected} s; first samples {:?} and {:?}, segments {:?}, applied {}",
            piecewise.first(),
            shifted.first(),
            o.segments,
            o.applied_s
        );
    }
}

//! A pair of sources measured through the reference's clock.
//!
//! **Why.** Two sources A and B each have a clock against the reference, m_A and m_B (the
//! evaluation's models: constant, linear or piecewise). Their relative clock is m_B − m_A: when A
//! drifts and B steps, a drift plus a step, which none of the three models expresses — measured
//! directly, such a pair gets a wrong headline and breaks every triple it is in. So the pair is
//! measured where its relative clock is simple: both sources' stamps mapped onto the reference's
//! clock first (A' = m_A(A), B' = m_B(B), the one clock correction), where B' against A' is a small
//! residual r, constant when the two models are right. The pair's clock is then
//!
//! Δt_AB(t) = m_B(t) − m_A(t) + r(t),
//!
//! and it is still a direct measurement of A against B: r carries only its own noise, σ_r, since the
//! models' errors are exactly what r measures (r = e_B − e_A, e the models' errors). The closure of
//! (R, A, B) is then e_B − e_A + noise of r, with σ² = σ_A² + σ_B² + σ_r²; the closure of three
//! sources (A, B, C) is r_AB + r_BC − r_AC, the models cancelling exactly. A source given a wrong
//! clock afterwards (an audit read back and edited) breaks the triples it is in as before.
//!
//! It is also cheaper: the pose fit starts at 0 without the signal searches, and the reference
//! role's stream is thinned to [`super::pairs::CHAINED_MAX_RATE_HZ`].
//!
//! **Shape.** The sum of three piecewise-linear clocks is piecewise-linear with one slope: segments
//! at the union of the three models' change times and one drift common to them (a piecewise clock
//! with `drift_ppm`). The drift is kept when it is significant (beyond 3σ of the three drifts' σ
//! combined: two sources on one drifting clock have two estimates of the same drift, whose
//! difference is noise). Segments shorter than [`MIN_SEGMENT_S`] (two models placing one step a few
//! seconds apart) are given to their neighbours, and neighbours whose offsets agree within 3σ are
//! merged; what remains decides the model.

use super::closure::{bounds, MARGIN_S, MIN_PIECE_S};
use super::report::Clock;
use crate::align::clock_model::OffsetModel;
use crate::report::json::{OffsetProfilePoint, OffsetSegmentReport};

/// A segment of a chained clock shorter than this, seconds, belongs to its neighbours (what the
/// closure test could not see either: two margins and its shortest piece).
pub const MIN_SEGMENT_S: f64 = 2.0 * MARGIN_S + MIN_PIECE_S;
/// Drifts and offsets within this many σ are the same.
const SAME_SIGMAS: f64 = 3.0;

/// A clock's drift and its σ, ppm (0 for a model without one).
fn drift_of(c: &Clock) -> (f64, f64) {
    match (c.model, c.drift_ppm) {
        (OffsetModel::Linear, Some(d)) | (OffsetModel::Piecewise, Some(d)) => {
            (d, c.drift_sigma_ppm.unwrap_or(0.0))
        }
        _ => (0.0, 0.0),
    }
}

/// The clock of pair (A, B) from A's and B's clocks against the reference and the residual `r`
/// measured between their corrected streams, over `span` (absolute seconds, the pair's overlap).
/// `None` when a clock has no value inside the span.
pub fn chained(to_a: &Clock, to_b: &Clock, r: &Clock, span: (f64, f64)) -> Option<Clock> {
    let value = |t: f64| -> Option<(f64, f64)> {
        let (a, b, x) = (to_a.at(t)?, to_b.at(t)?, r.at(t)?);
        Some((b.0 - a.0 + x.0, x.1))
    };
    let ((da, sa), (db, sb), (dr, sr)) = (drift_of(to_a), drift_of(to_b), drift_of(r));
    let drift = db - da + dr;
    let drift_sigma = sa.hypot(sb).hypot(sr);
    let keep_drift = drift != 0.0 && drift.abs() > SAME_SIGMAS * drift_sigma;
    let t_mid = 0.5 * (span.0 + span.1);
    // The drift's part of the value at t (Δt(t) = offset − drift·10⁻⁶·(t − t_mid)), when kept.
    let slope = |t: f64| {
        if keep_drift {
            -drift * 1e-6 * (t - t_mid)
        } else {
            0.0
        }
    };
    let mut segments = Vec::new();
    for w in bounds(&[to_a, to_b, r], span).windows(2) {
        let t = 0.5 * (w[0] + w[1]);
        let (v, sigma_s) = value(t)?;
        segments.push(OffsetSegmentReport {
            t_start: w[0],
            t_end: w[1],
            offset_s: v - slope(t),
            sigma_s,
        });
    }
    let segments = merge_same(absorb_short(segments));
    let (model, offset_s) = match (segments.len(), keep_drift) {
        (1, false) => (OffsetModel::Constant, segments[0].offset_s),
        (1, true) => (OffsetModel::Linear, segments[0].offset_s),
        _ => (
            OffsetModel::Piecewise,
            segments
                .iter()
                .max_by(|a, b| (a.t_end - a.t_start).total_cmp(&(b.t_end - b.t_start)))
                .map_or(f64::NAN, |s| s.offset_s),
        ),
    };
    let profile = r
        .profile
        .iter()
        .filter_map(|p| {
            let (a, b) = (to_a.at(p.t)?.0, to_b.at(p.t)?.0);
            Some(OffsetProfilePoint {
                offset_s: p.offset_s + b - a,
                ..p.clone()
            })
        })
        .collect();
    Some(Clock {
        model,
        offset_s,
        sigma_s: r.sigma_s,
        drift_ppm: keep_drift.then_some(drift),
        drift_sigma_ppm: keep_drift.then_some(drift_sigma),
        t_mid: keep_drift.then_some(t_mid),
        drift_resolution_ppm: None,
        segments: if model == OffsetModel::Linear {
            Vec::new()
        } else {
            segments
        },
        status: r.status,
        method: r.method,
        profile,
    })
}

/// Segments shorter than [`MIN_SEGMENT_S`] given to their neighbours (split at their middle).
fn absorb_short(mut segments: Vec<OffsetSegmentReport>) -> Vec<OffsetSegmentReport> {
    while segments.len() > 1 {
        let Some(k) = segments
            .iter()
            .enumerate()
            .filter(|(_, s)| s.t_end - s.t_start < MIN_SEGMENT_S)
            .min_by(|a, b| (a.1.t_end - a.1.t_start).total_cmp(&(b.1.t_end - b.1.t_start)))
            .map(|(k, _)| k)
        else {
            break;
        };
        let s = segments.remove(k);
        let mid = 0.5 * (s.t_start + s.t_end);
        match (k.checked_sub(1), segments.get(k).is_some()) {
            (Some(p), true) => {
                segments[p].t_end = mid;
                segments[k].t_start = mid;
            }
            (Some(p), false) => segments[p].t_end = s.t_end,
            (None, _) => segments[0].t_start = s.t_start,
        }
    }
    segments
}

/// Neighbouring segments whose offsets agree within 3σ merged (the longer one's offset and σ kept).
fn merge_same(segments: Vec<OffsetSegmentReport>) -> Vec<OffsetSegmentReport> {
    let mut out: Vec<OffsetSegmentReport> = Vec::with_capacity(segments.len());
    for s in segments {
        match out.last_mut() {
            Some(p)
                if (p.offset_s - s.offset_s).abs() <= SAME_SIGMAS * p.sigma_s.hypot(s.sigma_s) =>
            {
                if s.t_end - s.t_start > p.t_end - p.t_start {
                    p.offset_s = s.offset_s;
                    p.sigma_s = s.sigma_s;
                }
                p.t_end = s.t_end;
            }
            _ => out.push(s),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audit::report::examples;

    fn constant(offset_s: f64, sigma_s: f64) -> Clock {
        examples::constant(offset_s, sigma_s)
    }

    fn linear(offset_s: f64, drift_ppm: f64, t_mid: f64) -> Clock {
        examples::linear(offset_s, drift_ppm, t_mid, 0.001)
    }

    fn stepping(before: f64, after: f64, at: f64) -> Clock {
        examples::stepping(before, after, at, 0.001)
    }

    /// A drifting source against a stepping one: a step plus a drift, the value at every time the
    /// difference of the two clocks plus the residual, σ the residual's.
    #[test]
    fn a_drift_and_a_step_compose_exactly() {
        let a = linear(0.2, 100.0, 500.0);
        let b = stepping(0.1, 0.6, 400.0);
        let r = constant(0.002, 0.0005);
        let c = chained(&a, &b, &r, (0.0, 1000.0)).unwrap();
        assert_eq!(c.model, OffsetModel::Piecewise);
        assert!((c.drift_ppm.unwrap() + 100.0).abs() < 1e-9);
        for t in [50.0, 399.0, 401.0, 900.0] {
            let want = b.at(t).unwrap().0 - a.at(t).unwrap().0 + 0.002;
            let (got, sigma) = c.at(t).unwrap();
            assert!((got - want).abs() < 1e-9, "{t}: {got} against {want}");
            assert_eq!(sigma, 0.0005);
        }
    }

    /// Two sources on one drifting clock: drifts equal within their σ are no relative drift, and the
    /// pair is constant.
    #[test]
    fn one_drifting_clock_twice_is_constant() {
        let c = chained(
            &linear(0.2, 60.0, 500.0),
            &linear(0.2, 60.1, 500.0),
            &constant(0.0003, 0.0005),
            (0.0, 1000.0),
        )
        .unwrap();
        assert_eq!(c.model, OffsetModel::Constant);
        assert!((c.offset_s - 0.0003).abs() < 1e-9);
    }

    /// Two sources on one stepping clock whose steps were placed 4 s apart: the sliver between them
    /// goes to its neighbours, which then agree, so the pair is constant.
    #[test]
    fn one_step_placed_twice_is_constant() {
        let c = chained(
            &stepping(0.1, 0.6, 400.0),
            &stepping(0.1, 0.6, 404.0),
            &constant(0.0, 0.0005),
            (0.0, 1000.0),
        )
        .unwrap();
        assert_eq!(c.model, OffsetModel::Constant, "{c:?}");
        assert!(c.offset_s.abs() < 1e-9);
    }
}

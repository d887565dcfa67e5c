//! The closure of every triple of sources: Δt_AB + Δt_BC − Δt_AC, which is zero when the three
//! pairwise measurements agree (B's stamps onto A's clock, C's onto B's, and C's onto A's directly).
//!
//! The test is only as good as the σ each pair's evaluation reports: σ_closure² = σ_AB² + σ_BC² + σ_AC²
//! (the three are measured on different pairs of trajectories and taken as independent), and the
//! three σ are the evaluation's own (`time_offset.sigma_s`), so a better-calibrated σ makes a sharper
//! test with no change here.
//!
//! Clocks may drift or step, so the closure is taken piece by piece: the triple's common span is cut
//! at every change time of the three models, each piece trimmed by [`MARGIN_S`] on both sides (a
//! step located a few seconds off must not fail it), and the residual taken at each piece's middle.
//! χ² = Σ (r/σ)² over the pieces with one degree of freedom each; the triple is consistent when its
//! p-value is at least [`P_CONSISTENT`] (the two-sided 3σ of a Gaussian).
//!
//! A source whose measurements are out of line with the others breaks every triple it is in and no
//! other: [`out_of_line`] names the source such that every failing triple holds it and every triple
//! without it passes; failing that, the one pair whose measurement breaks exactly the triples holding
//! it (both sources agree with everyone else: the search went wrong on that pair). With three sources
//! every source is in the one triple, and none can be named.
//! A source whose stamps are shifted consistently (its whole stream on a wrong clock) moves all its
//! pairs together and closes every triple: that is its offset to the reference, not a closure failure.

use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::report::Clock;

/// Seconds left out on each side of a clock change.
pub const MARGIN_S: f64 = 15.0;
/// The shortest piece, seconds, taken into the test.
pub const MIN_PIECE_S: f64 = 10.0;
/// p-value below which a triple fails: 2·(1 − Φ(3)).
pub const P_CONSISTENT: f64 = 0.0027;

/// The closure of one triple.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosureStat {
    /// The residual and σ at the piece with the largest |r|/σ.
    pub residual_s: f64,
    pub sigma_s: f64,
    pub chi2: f64,
    pub dof: usize,
    pub p_value: f64,
    pub consistent: bool,
}

/// `span`'s ends and, sorted between them, every change time of `clocks` inside it: the bounds of
/// the pieces on which all of them are constant or linear.
pub fn bounds(clocks: &[&Clock], span: (f64, f64)) -> Vec<f64> {
    let mut cuts: Vec<f64> = clocks
        .iter()
        .flat_map(|c| c.breaks())
        .filter(|t| *t > span.0 && *t < span.1)
        .collect();
    cuts.sort_by(f64::total_cmp);
    let mut bounds = vec![span.0];
    bounds.extend(cuts);
    bounds.push(span.1);
    bounds
}

/// The closure of (A, B, C) from the clocks AB, BC and AC over `span` (absolute seconds, the three
/// sources' common span). `None` when no piece is long enough or a σ is missing.
pub fn closure(ab: &Clock, bc: &Clock, ac: &Clock, span: (f64, f64)) -> Option<ClosureStat> {
    let bounds = bounds(&[ab, bc, ac], span);
    let mut terms: Vec<(f64, f64)> = Vec::new();
    for (k, w) in bounds.windows(2).enumerate() {
        // The mission's own ends need no margin; a clock change does.
        let lo = if k == 0 { w[0] } else { w[0] + MARGIN_S };
        let hi = if k + 2 == bounds.len() {
            w[1]
        } else {
            w[1] - MARGIN_S
        };
        if hi - lo < MIN_PIECE_S {
            continue;
        }
        let t = 0.5 * (lo + hi);
        let (x, sx) = ab.at(t)?;
        let (y, sy) = bc.at(t)?;
        let (z, sz) = ac.at(t)?;
        let sigma = (sx * sx + sy * sy + sz * sz).sqrt();
        if !(sigma.is_finite() && sigma > 0.0) {
            return None;
        }
        terms.push((x + y - z, sigma));
    }
    if terms.is_empty() {
        return None;
    }
    let chi2: f64 = terms.iter().map(|(r, s)| (r / s).powi(2)).sum();
    let dof = terms.len();
    let p_value = ChiSquared::new(dof as f64).map_or(f64::NAN, |d| 1.0 - d.cdf(chi2));
    let (residual_s, sigma_s) = terms
        .iter()
        .copied()
        .max_by(|a, b| (a.0 / a.1).abs().total_cmp(&(b.0 / b.1).abs()))
        .unwrap_or((0.0, 0.0));
    Some(ClosureStat {
        residual_s,
        sigma_s,
        chi2,
        dof,
        p_value,
        consistent: p_value >= P_CONSISTENT,
    })
}

/// What the failing triples single out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Culprit {
    /// Every triple failing holds this source, every other triple closes.
    Source(usize),
    /// Every triple failing holds both, every other closes: that one pair's measurement is off
    /// (the two sources agree with everyone else).
    Pair(usize, usize),
    /// The failures do not single anything out (these sources are in every failing triple).
    Unclear(Vec<usize>),
}

/// Which source — or, failing that, which pair — the failing triples single out; `None` when every
/// triple closes.
pub fn out_of_line(n_sources: usize, triples: &[([usize; 3], bool)]) -> Option<Culprit> {
    if triples.iter().all(|(_, ok)| *ok) {
        return None;
    }
    let explains = |holds: &dyn Fn(&[usize; 3]) -> bool| {
        triples
            .iter()
            .all(|(t, ok)| if holds(t) { true } else { *ok })
            && triples.iter().any(|(t, ok)| holds(t) && !*ok)
    };
    let sources: Vec<usize> = (0..n_sources)
        .filter(|s| explains(&|t: &[usize; 3]| t.contains(s)))
        .collect();
    if let [one] = sources.as_slice() {
        return Some(Culprit::Source(*one));
    }
    let mut pairs = Vec::new();
    for a in 0..n_sources {
        for b in a + 1..n_sources {
            if explains(&|t: &[usize; 3]| t.contains(&a) && t.contains(&b))
                && triples
                    .iter()
                    .filter(|(t, _)| t.contains(&a) && t.contains(&b))
                    .all(|(_, ok)| !*ok)
            {
                pairs.push((a, b));
            }
        }
    }
    if let ([(a, b)], true) = (pairs.as_slice(), n_sources > 3) {
        return Some(Culprit::Pair(*a, *b));
    }
    let in_all: Vec<usize> = (0..n_sources)
        .filter(|s| triples.iter().all(|(t, ok)| *ok || t.contains(s)))
        .collect();
    Some(Culprit::Unclear(in_all))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audit::report::examples::{constant, stepping};

    #[test]
    fn consistent_offsets_close_and_a_bad_one_does_not() {
        let span = (0.0, 1000.0);
        let ok = closure(
            &constant(0.1, 0.005),
            &constant(0.2, 0.005),
            &constant(0.304, 0.005),
            span,
        )
        .unwrap();
        assert!(ok.consistent, "{ok:?}");
        assert!((ok.residual_s + 0.004).abs() < 1e-12);
        let bad = closure(
            &constant(0.1, 0.005),
            &constant(0.2, 0.005),
            &constant(0.35, 0.005),
            span,
        )
        .unwrap();
        assert!(!bad.consistent, "{bad:?}");
    }

    #[test]
    fn a_step_is_closed_piece_by_piece() {
        // B steps by −0.5 s at 400 s: AB and BC step, AC does not.
        let ab = stepping(0.3, -0.2, 400.0, 0.005);
        let bc = stepping(-0.1, 0.4, 401.0, 0.005);
        let ac = constant(0.2, 0.005);
        let c = closure(&ab, &bc, &ac, (0.0, 1000.0)).unwrap();
        assert!(c.consistent, "{c:?}");
        assert_eq!(c.dof, 2);
    }

    #[test]
    fn the_source_in_every_failing_triple_is_named() {
        // Four sources; source 2's pairs are off: the triples holding it fail.
        let triples = [
            ([0, 1, 2], false),
            ([0, 1, 3], true),
            ([0, 2, 3], false),
            ([1, 2, 3], false),
        ];
        assert_eq!(out_of_line(4, &triples), Some(Culprit::Source(2)));
        // One pair off (1–3): the two triples holding both fail.
        let triples = [
            ([0, 1, 2], true),
            ([0, 1, 3], false),
            ([0, 2, 3], true),
            ([1, 2, 3], false),
        ];
        assert_eq!(out_of_line(4, &triples), Some(Culprit::Pair(1, 3)));
        // Three sources: the one triple holds them all.
        assert_eq!(
            out_of_line(3, &[([0, 1, 2], false)]),
            Some(Culprit::Unclear(vec![0, 1, 2]))
        );
        assert_eq!(out_of_line(3, &[([0, 1, 2], true)]), None);
    }
}

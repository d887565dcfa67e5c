//! A source's stream: its rate (median sample period), its gaps and when it has data on the
//! reference's clock.
//!
//! A gap is an interval between consecutive samples longer than five median periods and at least
//! 0.5 s: a dropped message or two is jitter, a recorder or sensor outage is a gap. Coverage maps the
//! first and last stamp through the source's clock correction and counts the reference's span
//! covered with the gaps left out.

use super::report::{Coverage, Gaps};
use crate::clock::ClockCorrection;
use crate::trajectory::Trajectory;

/// The smallest gap, seconds, whatever the rate.
pub const MIN_GAP_S: f64 = 0.5;
/// A gap is longer than this many median periods.
pub const GAP_PERIODS: f64 = 5.0;

/// The gaps of `t`.
pub fn gaps(t: &Trajectory) -> Gaps {
    let threshold_s = t
        .median_period_s()
        .map_or(MIN_GAP_S, |p| (GAP_PERIODS * p).max(MIN_GAP_S));
    let mut g = Gaps {
        threshold_s,
        ..Gaps::default()
    };
    for w in t.stamps_ns.windows(2) {
        let d = (w[1] - w[0]) as f64 * 1e-9;
        if d > threshold_s {
            g.count += 1;
            g.total_s += d;
            g.longest_s = g.longest_s.max(d);
        }
    }
    g
}

/// When `t` has data on the reference clock (stamps mapped by `clock`), and the share of the
/// reference's span `[r0, r1]` (absolute seconds) it covers, its gaps left out.
pub fn coverage(t: &Trajectory, clock: &ClockCorrection, (r0, r1): (f64, f64)) -> Coverage {
    let map = |ns: i64| clock.stamp(ns).unwrap_or(ns) as f64 * 1e-9;
    let (Some(&first), Some(&last)) = (t.stamps_ns.first(), t.stamps_ns.last()) else {
        return Coverage::default();
    };
    let (t_start, t_end) = (map(first), map(last));
    let g = gaps(t);
    let span = (r1 - r0).max(1e-9);
    let inside = (t_end.min(r1) - t_start.max(r0)).max(0.0);
    // Gaps are measured on the source's clock; its rate differs from the reference's by ppm.
    let covered = (inside - g.total_s.min(inside)).max(0.0);
    Coverage {
        t_start,
        t_end,
        fraction_of_reference: (covered / span).clamp(0.0, 1.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn stamps(s: &[f64]) -> Trajectory {
        let mut t = Trajectory::new(false);
        for &x in s {
            t.push((x * 1e9) as i64, Vector3::zeros(), None);
        }
        t
    }

    #[test]
    fn a_gap_is_five_periods_and_half_a_second() {
        let mut s: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        s.extend((0..100).map(|i| 12.0 + i as f64 * 0.1));
        let t = stamps(&s);
        assert!((t.median_period_s().unwrap() - 0.1).abs() < 1e-9);
        let g = gaps(&t);
        assert_eq!(g.count, 1);
        assert!((g.longest_s - 2.1).abs() < 1e-9);
        let c = coverage(&t, &ClockCorrection::Constant { dt_ns: 0 }, (0.0, 21.9));
        assert!((c.fraction_of_reference - (21.9 - 2.1) / 21.9).abs() < 1e-9);
        // Jitter of a dropped message is no gap.
        let t = stamps(&[0.0, 0.1, 0.3, 0.4]);
        assert_eq!(gaps(&t).count, 0);
    }
}

//! Path length measured on an ε-decimated polyline.
//!
//! Summing the raw steps of a noisy trajectory measures the noise: with 2 cm of position noise and 2 cm
//! steps (a legged robot at 0.3 m/s, 20 Hz) the raw polyline is tens of percent too long. Skipping every
//! sample closer than ε to the last kept one makes each chord at least ε long, so the noise adds only
//! about σ²/ε per chord. Both trajectories of a Drift Error comparison are measured this way, with the
//! same ε, over the same time spans.
//!
//! Excluded intervals (rotations in place, see [`super::rotation_in_place`]) count zero length: points are
//! interpolated at their boundaries and always kept, so that no chord straddles a boundary.
//!
//! Hand-written: the rule is two lines and must share its vertices with the windowing and the lever-arm
//! correction; no crate offers it.

use nalgebra::Vector3;

/// The position of a trajectory at time `t`, linear between the two samples around it (clamped to the
/// first or last sample outside the time range). `times` must be increasing and non-empty.
pub fn interpolate_position(times: &[f64], positions: &[Vector3<f64>], t: f64) -> Vector3<f64> {
    let n = times.len().min(positions.len());
    let k = times[..n].partition_point(|&x| x <= t);
    if k == 0 {
        return positions[0];
    }
    if k >= n {
        return positions[n - 1];
    }
    let (t0, t1) = (times[k - 1], times[k]);
    let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    positions[k - 1] + (positions[k] - positions[k - 1]) * f
}

/// True when `t` lies inside one of the sorted, disjoint `intervals`.
pub(crate) fn in_intervals(intervals: &[[f64; 2]], t: f64) -> bool {
    let k = intervals.partition_point(|iv| iv[1] < t);
    k < intervals.len() && intervals[k][0] <= t
}

/// A trajectory's ε-decimated polyline with its cumulative counted length. The first sample, then every sample at
/// least ε from the last kept one; the last sample is always a vertex.
#[derive(Debug, Clone)]
pub struct DecimatedPath<'a> {
    raw_t: &'a [f64],
    raw_p: &'a [Vector3<f64>],
    /// Times of the polyline's vertices (kept samples and excluded-interval boundaries), seconds.
    pub t: Vec<f64>,
    /// Positions of the vertices, metres.
    pub p: Vec<Vector3<f64>>,
    /// Cumulative counted length at each vertex, metres (chords inside excluded intervals count zero).
    pub s: Vec<f64>,
    /// Number of input samples.
    pub n_samples: usize,
    /// Number of input samples the decimation skipped.
    pub skipped: usize,
}

impl<'a> DecimatedPath<'a> {
    /// Decimates `positions` (at increasing `times`, seconds) with `eps_m`; chords inside the sorted,
    /// disjoint `excluded` intervals count zero length.
    pub fn new(
        times: &'a [f64],
        positions: &'a [Vector3<f64>],
        eps_m: f64,
        excluded: &[[f64; 2]],
    ) -> Self {
        let n = times.len().min(positions.len());
        let (raw_t, raw_p) = (&times[..n], &positions[..n]);
        let mut path = DecimatedPath {
            raw_t,
            raw_p,
            t: Vec::new(),
            p: Vec::new(),
            s: Vec::new(),
            n_samples: n,
            skipped: 0,
        };
        if n == 0 {
            return path;
        }
        // Boundaries of excluded intervals strictly inside the time range become forced vertices.
        let mut bounds: Vec<f64> = excluded
            .iter()
            .flat_map(|iv| [iv[0], iv[1]])
            .filter(|&b| b > raw_t[0] && b < raw_t[n - 1])
            .collect();
        bounds.sort_by(f64::total_cmp);
        bounds.dedup();
        let mut next_bound = 0;
        for i in 0..n {
            let ti = raw_t[i];
            while next_bound < bounds.len() && bounds[next_bound] < ti {
                let b = bounds[next_bound];
                path.push_vertex(b, interpolate_position(raw_t, raw_p, b), excluded);
                next_bound += 1;
            }
            let forced = next_bound < bounds.len() && bounds[next_bound] == ti;
            if forced {
                next_bound += 1;
            }
            // The last sample is always kept, so the path spans the whole trajectory.
            let keep = forced
                || i == n - 1
                || path.p.last().is_none_or(|l| (raw_p[i] - l).norm() >= eps_m);
            if keep {
                path.push_vertex(ti, raw_p[i], excluded);
            } else {
                path.skipped += 1;
            }
        }
        path
    }

    fn push_vertex(&mut self, t: f64, p: Vector3<f64>, excluded: &[[f64; 2]]) {
        let s = match (self.t.last(), self.p.last(), self.s.last()) {
            (Some(&t0), Some(p0), Some(&s0)) => {
                if in_intervals(excluded, 0.5 * (t0 + t)) {
                    s0
                } else {
                    s0 + (p - p0).norm()
                }
            }
            _ => 0.0,
        };
        self.t.push(t);
        self.p.push(p);
        self.s.push(s);
    }

    /// Fraction of the input samples the decimation skipped.
    pub fn discarded_fraction(&self) -> f64 {
        if self.n_samples == 0 {
            0.0
        } else {
            self.skipped as f64 / self.n_samples as f64
        }
    }

    /// Counted path length from the first vertex to time `t`, metres. Inside a chord, the trajectory is
    /// interpolated (linearly) at `t` and projected on the chord, so a window end falling in the middle
    /// of a chord gets the part of the chord already travelled; outside the vertices' span it is clamped.
    pub fn length_at(&self, t: f64) -> f64 {
        let m = self.t.len();
        if m == 0 {
            return 0.0;
        }
        let k = self.t.partition_point(|&x| x <= t);
        if k == 0 {
            return self.s[0];
        }
        if k >= m {
            return self.s[m - 1];
        }
        let (a, b) = (k - 1, k);
        let ds = self.s[b] - self.s[a];
        if ds <= 0.0 {
            return self.s[a];
        }
        let chord = self.p[b] - self.p[a];
        let c2 = chord.norm_squared();
        if c2 <= 0.0 {
            return self.s[a];
        }
        let q = interpolate_position(self.raw_t, self.raw_p, t);
        let f = ((q - self.p[a]).dot(&chord) / c2).clamp(0.0, 1.0);
        self.s[a] + f * ds
    }

    /// Counted path length between times `t0` and `t1`, metres (additive: lengths of adjacent spans sum).
    pub fn length_between(&self, t0: f64, t1: f64) -> f64 {
        (self.length_at(t1) - self.length_at(t0)).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize, step: f64) -> (Vec<f64>, Vec<Vector3<f64>>) {
        (0..n)
            .map(|i| (i as f64 * 0.1, Vector3::new(i as f64 * step, 0.0, 0.0)))
            .unzip()
    }

    #[test]
    fn length_on_a_line_and_partial_chords() {
        let (t, p) = line(101, 0.1); // 10 m in 10 s
        let path = DecimatedPath::new(&t, &p, 0.5, &[]);
        assert_eq!(path.skipped, 80);
        assert!((path.discarded_fraction() - 80.0 / 101.0).abs() < 1e-12);
        assert!((path.length_between(0.0, 10.0) - 10.0).abs() < 1e-9);
        // Window ends inside chords are interpolated.
        assert!((path.length_between(1.23, 7.77) - 6.54).abs() < 1e-9);
    }

    #[test]
    fn excluded_intervals_count_zero() {
        let (t, p) = line(101, 0.1);
        let path = DecimatedPath::new(&t, &p, 0.5, &[[2.25, 4.05]]);
        assert!((path.length_between(0.0, 10.0) - (10.0 - 1.8)).abs() < 1e-9);
        assert!(path.length_between(2.5, 4.0).abs() < 1e-12);
    }
}

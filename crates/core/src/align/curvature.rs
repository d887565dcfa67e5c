//! The curvature signature of a trajectory: eq. (1) of the paper.
//!
//! For each sample i, take the nearest sample before (j) and after (k) whose chord to i is at least
//! ε_min long; Δθ is the turning angle between the chords p_i − p_j and p_k − p_i, and
//! κ_i = 2Δθ / (Δs₁ + Δs₂). A sample is skipped when Δθ > θ_max (a discontinuity) or when either chord
//! took Δt_max or longer (the robot was standing still). κ depends only on distances and angles, so it is
//! the same in any frame: that is what lets two trajectories in unrelated frames be compared.

use nalgebra::Vector3;

/// The parameters of eq. (1).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CurvatureParams {
    /// ε_min: the shortest chord, metres.
    pub eps_m: f64,
    /// θ_max: the largest turning angle kept, radians.
    pub theta_max_rad: f64,
    /// Δt_max: a chord that takes this long or longer marks a stationary robot, seconds.
    pub dt_max_s: f64,
}

impl Default for CurvatureParams {
    /// The paper's values for a legged robot.
    fn default() -> Self {
        CurvatureParams {
            eps_m: 0.1,
            theta_max_rad: std::f64::consts::FRAC_PI_2,
            dt_max_s: 2.0,
        }
    }
}

/// One defined sample of the signature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvatureSample {
    /// Index of the sample in the input.
    pub index: usize,
    /// Its time, seconds.
    pub t: f64,
    /// κ_i, 1/m (unsigned, as in the paper).
    pub curvature: f64,
    /// Δθ, radians.
    pub turn_rad: f64,
    /// Signed turn in the horizontal plane (positive counter-clockwise about +z), radians.
    pub turn_signed_rad: f64,
    /// Δs₁ and Δs₂, metres.
    pub chord_before_m: f64,
    pub chord_after_m: f64,
}

impl CurvatureSample {
    /// Signed horizontal curvature 2·Δθ_z/(Δs₁+Δs₂), 1/m.
    pub fn signed_curvature(&self) -> f64 {
        2.0 * self.turn_signed_rad / (self.chord_before_m + self.chord_after_m)
    }
}

/// Computes eq. (1) at every sample where it is defined. `times` (seconds) must be increasing and as long
/// as `positions`. Samples where κ is undefined (no ε-chord on one side, Δθ > θ_max, a chord slower than
/// Δt_max) are absent from the result.
///
/// ```
/// use nalgebra::Vector3;
/// use trajdrift_core::align::curvature::{curvature_signature, CurvatureParams};
/// // A circle of radius 2 m sampled every 0.05 rad.
/// let (t, p): (Vec<f64>, Vec<Vector3<f64>>) = (0..400)
///     .map(|i| { let a = i as f64 * 0.05; (i as f64 * 0.1, Vector3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0)) })
///     .unzip();
/// let sig = curvature_signature(&t, &p, &CurvatureParams::default());
/// assert!(sig.iter().all(|s| (s.curvature - 0.5).abs() < 0.01));
/// ```
pub fn curvature_signature(
    times: &[f64],
    positions: &[Vector3<f64>],
    params: &CurvatureParams,
) -> Vec<CurvatureSample> {
    let mut out = Vec::new();
    curvature_signature_each(times, positions, params, |s| out.push(s));
    out
}

/// [`curvature_signature`], each defined sample handed to `out` as it is computed (the caller keeps
/// what it needs, not 56 bytes a sample).
pub fn curvature_signature_each(
    times: &[f64],
    positions: &[Vector3<f64>],
    params: &CurvatureParams,
    mut out: impl FnMut(CurvatureSample),
) {
    let n = times.len().min(positions.len());
    let chords = Chords::new(&times[..n], &positions[..n], params);
    for i in 0..n {
        let pi = positions[i];
        let Some(j) = chords.before(i) else { continue };
        let Some(k) = chords.after(i) else { continue };
        let a = pi - positions[j];
        let b = positions[k] - pi;
        let (s1, s2) = (a.norm(), b.norm());
        let turn = turning_angle(&a, &b);
        if turn.is_nan() || turn > params.theta_max_rad {
            continue;
        }
        out(CurvatureSample {
            index: i,
            t: times[i],
            curvature: 2.0 * turn / (s1 + s2),
            turn_rad: turn,
            turn_signed_rad: signed_horizontal_turn(&a, &b),
            chord_before_m: s1,
            chord_after_m: s2,
        });
    }
}

/// Samples per block of the chord search's first level; the second level groups this many blocks.
const CHORD_BLOCK: usize = 16;

/// The search for the nearest ε-chord on each side of a sample, in blocks: a block whose bounding box
/// lies wholly within ε of p_i cannot hold the chord and is skipped at once (a robot standing still
/// for Δt_max = 30 s at 200 Hz would otherwise cost 6000 distance checks per sample). The answer is the
/// sample-by-sample scan's: rounding is monotone, so a point's computed squared distance never exceeds
/// its box's, and a skipped block is one where the scan would only have moved on (or stopped at a
/// time past Δt_max, which the next check after the block sees too: times increase).
struct Chords<'a> {
    t: &'a [f64],
    p: &'a [Vector3<f64>],
    eps2: f64,
    dt_max: f64,
    /// Bounding boxes of blocks of CHORD_BLOCK samples, then of CHORD_BLOCK² samples.
    small: Vec<[Vector3<f64>; 2]>,
    large: Vec<[Vector3<f64>; 2]>,
}

impl<'a> Chords<'a> {
    fn new(t: &'a [f64], p: &'a [Vector3<f64>], params: &CurvatureParams) -> Chords<'a> {
        let boxes = |size: usize| -> Vec<[Vector3<f64>; 2]> {
            p.chunks(size)
                .map(|c| {
                    c.iter()
                        .fold([c[0], c[0]], |[lo, hi], q| [lo.inf(q), hi.sup(q)])
                })
                .collect()
        };
        Chords {
            t,
            p,
            eps2: params.eps_m * params.eps_m,
            dt_max: params.dt_max_s,
            small: boxes(CHORD_BLOCK),
            large: boxes(CHORD_BLOCK * CHORD_BLOCK),
        }
    }

    /// Whether every point of the box `b` is closer than ε to `q`.
    fn inside(&self, q: &Vector3<f64>, b: &[Vector3<f64>; 2]) -> bool {
        let far = |k: usize| (q[k] - b[0][k]).abs().max((q[k] - b[1][k]).abs());
        let (x, y, z) = (far(0), far(1), far(2));
        x * x + y * y + z * z < self.eps2
    }

    /// The whole block of `size` samples starting at `k`, when it is aligned and complete.
    fn block(&self, k: usize, size: usize) -> Option<&[Vector3<f64>; 2]> {
        let boxes = if size == CHORD_BLOCK {
            &self.small
        } else {
            &self.large
        };
        (k % size == 0 && k + size <= self.p.len()).then(|| &boxes[k / size])
    }

    /// The nearest k > i with |p_k − p_i| ≥ ε, unless a sample Δt_max or more after i comes first.
    fn after(&self, i: usize) -> Option<usize> {
        let (n, pi) = (self.p.len(), self.p[i]);
        let mut k = i + 1;
        while k < n {
            if self.t[k] - self.t[i] >= self.dt_max {
                return None;
            }
            if let Some(b) = self.block(k, CHORD_BLOCK * CHORD_BLOCK) {
                if self.inside(&pi, b) {
                    k += CHORD_BLOCK * CHORD_BLOCK;
                    continue;
                }
            }
            if let Some(b) = self.block(k, CHORD_BLOCK) {
                if self.inside(&pi, b) {
                    k += CHORD_BLOCK;
                    continue;
                }
            }
            if (self.p[k] - pi).norm_squared() >= self.eps2 {
                return Some(k);
            }
            k += 1;
        }
        None
    }

    /// The nearest j < i with |p_i − p_j| ≥ ε, unless a sample Δt_max or more before i comes first.
    fn before(&self, i: usize) -> Option<usize> {
        let pi = self.p[i];
        // `end` is one past the candidate: the candidate is end − 1.
        let mut end = i;
        while end > 0 {
            let j = end - 1;
            if self.t[i] - self.t[j] >= self.dt_max {
                return None;
            }
            let skip = |size: usize| {
                end >= size
                    && self
                        .block(end - size, size)
                        .is_some_and(|b| self.inside(&pi, b))
            };
            if skip(CHORD_BLOCK * CHORD_BLOCK) {
                end -= CHORD_BLOCK * CHORD_BLOCK;
                continue;
            }
            if skip(CHORD_BLOCK) {
                end -= CHORD_BLOCK;
                continue;
            }
            if (pi - self.p[j]).norm_squared() >= self.eps2 {
                return Some(j);
            }
            end -= 1;
        }
        None
    }
}

/// The angle between two chords, in [0, π], computed with atan2 (accurate for small angles, where
/// acos of a dot product loses half the digits).
pub fn turning_angle(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// The signed turn between the horizontal projections of two chords, in (−π, π], positive
/// counter-clockwise about +z.
pub fn signed_horizontal_turn(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let cross = a.x * b.y - a.y * b.x;
    let dot = a.x * b.x + a.y * b.y;
    cross.atan2(dot)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(r: f64, step_rad: f64, n: usize) -> (Vec<f64>, Vec<Vector3<f64>>) {
        (0..n)
            .map(|i| {
                let a = i as f64 * step_rad;
                (i as f64 * 0.1, Vector3::new(r * a.cos(), r * a.sin(), 0.0))
            })
            .unzip()
    }

    #[test]
    fn circle_curvature_matches_chord_formula() {
        // On a circle, chords of angle φ subtend length 2r·sin(φ/2) and turn by φ, so eq. (1) gives
        // κ = φ / (2r sin(φ/2)): 1/r to second order in φ.
        let (t, p) = circle(5.0, 0.02, 500);
        let sig = curvature_signature(
            &t,
            &p,
            &CurvatureParams {
                eps_m: 0.3,
                ..Default::default()
            },
        );
        assert!(sig.len() > 400);
        for s in &sig {
            let phi = s.turn_rad;
            let expected = phi / (2.0 * 5.0 * (phi / 2.0).sin());
            assert!(
                (s.curvature - expected).abs() < 1e-9,
                "{} vs {}",
                s.curvature,
                expected
            );
            assert!((s.curvature - 0.2).abs() < 1e-3);
            assert!(s.signed_curvature() > 0.0);
        }
    }

    /// The sample-by-sample scan of eq. (1)'s chords, as first written.
    fn scan(
        t: &[f64],
        p: &[Vector3<f64>],
        params: &CurvatureParams,
        i: usize,
    ) -> Option<(usize, usize)> {
        let eps2 = params.eps_m * params.eps_m;
        let before = (0..i)
            .rev()
            .take_while(|&j| t[i] - t[j] < params.dt_max_s)
            .find(|&j| (p[i] - p[j]).norm_squared() >= eps2)?;
        let after = (i + 1..p.len())
            .take_while(|&k| t[k] - t[i] < params.dt_max_s)
            .find(|&k| (p[k] - p[i]).norm_squared() >= eps2)?;
        Some((before, after))
    }

    #[test]
    fn the_block_search_finds_the_scans_chords() {
        // A noisy walk at 200 Hz with stands (noise only) of 0.5 to 20 s, turns and a jump.
        let mut x = 7u64;
        let mut rnd = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (mut t, mut p) = (vec![], vec![]);
        let (mut pos, mut heading) = (Vector3::zeros(), 0.0f64);
        for i in 0..40_000usize {
            let standing = (i / 1500) % 3 == 1 || (i / 333) % 7 == 3;
            if !standing {
                heading += 0.02 * rnd();
                pos += Vector3::new(heading.cos(), heading.sin(), 0.1 * rnd()) * 0.005;
            }
            if i == 20_000 {
                pos.x += 3.0;
            }
            t.push(i as f64 * 0.005);
            p.push(pos + Vector3::new(rnd(), rnd(), rnd()) * 0.004);
        }
        for params in [
            CurvatureParams::default(),
            CurvatureParams {
                eps_m: 0.5,
                dt_max_s: 30.0,
                ..Default::default()
            },
            CurvatureParams {
                eps_m: 0.01,
                dt_max_s: 0.5,
                ..Default::default()
            },
        ] {
            let chords = Chords::new(&t, &p, &params);
            for i in 0..t.len() {
                let fast = chords.before(i).zip(chords.after(i));
                assert_eq!(fast, scan(&t, &p, &params, i), "sample {i}, {params:?}");
            }
        }
    }

    #[test]
    fn stationary_and_discontinuities_are_skipped() {
        // Stand still for 5 s, then a hairpin (a 180° reversal).
        let mut t = vec![];
        let mut p = vec![];
        for i in 0..50 {
            t.push(i as f64 * 0.1);
            p.push(Vector3::zeros());
        }
        for i in 0..20 {
            t.push(5.0 + i as f64 * 0.1);
            p.push(Vector3::new(i as f64 * 0.2, 0.0, 0.0));
        }
        for i in 0..20 {
            t.push(7.0 + i as f64 * 0.1);
            p.push(Vector3::new(3.8 - i as f64 * 0.2, 0.0, 0.0));
        }
        let sig = curvature_signature(&t, &p, &CurvatureParams::default());
        assert!(
            sig.iter().all(|s| s.index >= 50),
            "stationary samples must be skipped"
        );
        assert!(sig
            .iter()
            .all(|s| s.turn_rad <= std::f64::consts::FRAC_PI_2));
        assert!(
            !sig.iter().any(|s| s.index == 69),
            "the reversal is a discontinuity"
        );
    }
}

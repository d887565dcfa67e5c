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
/// use trajdrift::align::curvature::{curvature_signature, CurvatureParams};
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
    let n = times.len().min(positions.len());
    let eps2 = params.eps_m * params.eps_m;
    let mut out = Vec::new();
    for i in 0..n {
        let pi = positions[i];
        // Nearest sample before i with a chord of at least ε, within Δt_max.
        let mut before = None;
        let mut j = i;
        while j > 0 {
            j -= 1;
            if times[i] - times[j] >= params.dt_max_s {
                break;
            }
            if (pi - positions[j]).norm_squared() >= eps2 {
                before = Some(j);
                break;
            }
        }
        let Some(j) = before else { continue };
        let mut after = None;
        for k in i + 1..n {
            if times[k] - times[i] >= params.dt_max_s {
                break;
            }
            if (positions[k] - pi).norm_squared() >= eps2 {
                after = Some(k);
                break;
            }
        }
        let Some(k) = after else { continue };
        let a = pi - positions[j];
        let b = positions[k] - pi;
        let (s1, s2) = (a.norm(), b.norm());
        let turn = turning_angle(&a, &b);
        if turn.is_nan() || turn > params.theta_max_rad {
            continue;
        }
        out.push(CurvatureSample {
            index: i,
            t: times[i],
            curvature: 2.0 * turn / (s1 + s2),
            turn_rad: turn,
            turn_signed_rad: signed_horizontal_turn(&a, &b),
            chord_before_m: s1,
            chord_after_m: s2,
        });
    }
    out
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

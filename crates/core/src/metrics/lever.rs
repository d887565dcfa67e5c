//! The paper's lever-arm correction of the Drift Error.
//!
//! Two sensors on one rigid body turn by the same angle Δθ on concentric arcs, so their path lengths
//! differ by the ratio of their radii: Δs_ref/Δs_est = r_ref/r_est = α. The paper applies one α per
//! window, which is ambiguous when the curvature varies inside the window; here α is applied per
//! *curvature segment*: the segments are the chords between consecutive vertices of the reference's
//! ε-decimated polyline (the same chords whose lengths make the window), and the curvature of each
//! trajectory on a segment is the mean of its defined eq. (1) samples over the segment's time span (or,
//! when none falls inside, the linear interpolation of its neighbours at the segment's middle, if both are
//! within Δt_max). Then r = 1/κ, and
//!
//! α_seg = r_ref/r_est when both radii are defined, neither is ~0 (below the lever arm a: a rotation
//! about a point near a sensor, handled by `super::rotation_in_place`) and |r_est − r_ref| ≤ a; else 1.
//!
//! The corrected estimate length of a window is Σ α_seg·Δs_est,seg and its reported α is
//! corrected / raw estimate length.
//!
//! Note: a distance-scale error s of the estimate scales r_est by (1 + s) too, so on a corrected segment
//! α_seg also cancels the scale error. The threshold a limits the correction to turns where
//! s·r ≤ a, i.e. tight ones; on straights r is large and noisy and α stays 1.

use crate::align::curvature::CurvatureSample;

/// Whether the Drift Error corrects for the lever arm between the two sensors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LeverCorrection {
    /// The paper's correction α = r_ref/r_est, per curvature segment.
    Paper,
    /// No correction (α = 1).
    None,
    /// Beyond the paper: fit the scale s and the lateral lever arm d of L_est = s·(L_ref − d·Δψ) over
    /// all windows, and correct each window by d ([`super::lever_fit`]). The default: closest to the
    /// truth on the shared missions (tests/it/lever_fit.rs `correction_table`).
    #[default]
    Fit,
}

impl std::fmt::Display for LeverCorrection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

impl LeverCorrection {
    /// The name used on the command line and in reports.
    pub fn as_str(&self) -> &'static str {
        match self {
            LeverCorrection::Paper => "paper",
            LeverCorrection::None => "none",
            LeverCorrection::Fit => "fit",
        }
    }
}

impl std::str::FromStr for LeverCorrection {
    type Err = crate::Error;

    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "paper" => Ok(LeverCorrection::Paper),
            "none" => Ok(LeverCorrection::None),
            "fit" => Ok(LeverCorrection::Fit),
            _ => Err(crate::Error::InvalidArgument(format!(
                "lever correction `{s}`: expected `fit`, `paper` or `none`"
            ))),
        }
    }
}

/// The defined curvature samples of one trajectory, for means over time spans.
#[derive(Debug, Clone)]
pub struct CurvatureTrack {
    t: Vec<f64>,
    k: Vec<f64>,
    prefix: Vec<f64>,
    dt_max_s: f64,
}

impl CurvatureTrack {
    /// Builds the track from an eq. (1) signature (in time order); `dt_max_s` bounds interpolation.
    pub fn new(samples: &[CurvatureSample], dt_max_s: f64) -> Self {
        let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
        let k: Vec<f64> = samples.iter().map(|s| s.curvature).collect();
        let mut prefix = Vec::with_capacity(k.len() + 1);
        prefix.push(0.0);
        for &x in &k {
            prefix.push(prefix.last().copied().unwrap_or(0.0) + x);
        }
        CurvatureTrack {
            t,
            k,
            prefix,
            dt_max_s,
        }
    }

    /// Mean curvature over `[t0, t1]`, 1/m; `None` where the signature is undefined there.
    pub fn mean_between(&self, t0: f64, t1: f64) -> Option<f64> {
        let i0 = self.t.partition_point(|&x| x < t0);
        let i1 = self.t.partition_point(|&x| x <= t1);
        if i1 > i0 {
            return Some((self.prefix[i1] - self.prefix[i0]) / (i1 - i0) as f64);
        }
        // No sample inside: interpolate the neighbours at the middle when both are close enough.
        if i0 == 0 || i0 >= self.t.len() {
            return None;
        }
        let tm = 0.5 * (t0 + t1);
        let (ta, tb) = (self.t[i0 - 1], self.t[i0]);
        if tm - ta > self.dt_max_s || tb - tm > self.dt_max_s || tb <= ta {
            return None;
        }
        let f = (tm - ta) / (tb - ta);
        Some(self.k[i0 - 1] + f * (self.k[i0] - self.k[i0 - 1]))
    }
}

/// α of one curvature segment from the two mean curvatures (1/m) and the expected lever arm `a` (m).
///
/// ```
/// use trajdrift_core::metrics::lever::segment_alpha;
/// // Concentric arcs of radius 4 m and 4.08 m: α = 4/4.08.
/// assert!((segment_alpha(Some(0.25), Some(1.0 / 4.08), 0.1) - 4.0 / 4.08).abs() < 1e-12);
/// // Radii 0.5 m apart with a = 0.1 m: not the same turn, no correction.
/// assert_eq!(segment_alpha(Some(0.25), Some(1.0 / 4.5), 0.1), 1.0);
/// ```
pub fn segment_alpha(kappa_ref: Option<f64>, kappa_est: Option<f64>, lever_arm_m: f64) -> f64 {
    let (Some(kr), Some(ke)) = (kappa_ref, kappa_est) else {
        return 1.0;
    };
    if !(kr > 0.0 && ke > 0.0 && kr.is_finite() && ke.is_finite()) {
        return 1.0;
    }
    let (r_ref, r_est) = (1.0 / kr, 1.0 / ke);
    let r_min = lever_arm_m.max(1e-3);
    if r_ref < r_min || r_est < r_min {
        return 1.0;
    }
    if (r_est - r_ref).abs() <= lever_arm_m {
        r_ref / r_est
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for c in [
            LeverCorrection::Paper,
            LeverCorrection::None,
            LeverCorrection::Fit,
        ] {
            assert_eq!(c.as_str().parse::<LeverCorrection>().unwrap(), c);
            assert_eq!(
                serde_json::to_string(&c).unwrap(),
                format!("\"{}\"", c.as_str())
            );
        }
        assert!("Paper!".parse::<LeverCorrection>().is_err());
    }

    #[test]
    fn alpha_rules() {
        assert_eq!(segment_alpha(None, Some(0.2), 0.1), 1.0);
        assert_eq!(segment_alpha(Some(50.0), Some(40.0), 0.1), 1.0); // radii ~0
        assert_eq!(segment_alpha(Some(0.0), Some(0.2), 0.1), 1.0);
        assert!((segment_alpha(Some(0.5), Some(1.0 / 2.05), 0.1) - 2.0 / 2.05).abs() < 1e-12);
    }

    #[test]
    fn track_means_and_interpolates() {
        let mk = |t: f64, k: f64| CurvatureSample {
            index: 0,
            t,
            curvature: k,
            turn_rad: 0.0,
            turn_signed_rad: 0.0,
            chord_before_m: 0.1,
            chord_after_m: 0.1,
        };
        let tr = CurvatureTrack::new(&[mk(0.0, 1.0), mk(1.0, 3.0), mk(10.0, 5.0)], 2.0);
        assert_eq!(tr.mean_between(-0.5, 1.5), Some(2.0));
        assert_eq!(tr.mean_between(0.25, 0.75), Some(2.0));
        assert_eq!(tr.mean_between(4.0, 6.0), None);
        assert_eq!(tr.mean_between(11.0, 12.0), None);
    }
}

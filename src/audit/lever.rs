//! A source's lever arm relative to the reference point.
//!
//! **With orientation** (odometry, poses): the lever the evaluation's pose fit measured together
//! with Δt when it aligned the source with the reference
//! ([`crate::align::pose_fit`]: reference ≈ source position − R_src·ℓ, each window of the mission
//! its own similarity to the reference's frame; σ by the jackknife over windows). The audit does not fit it
//! a second time: one definition of the lever, measured once, and the one whose Δt the clock
//! model uses. `lever_m` is ℓ, the source's sensor relative to the reference point in the source's
//! body frame (x forward, y left, z up).
//!
//! **What the path can tell.** Turning informs the horizontal lever; tilting the vertical one. The
//! pose fit's prior keeps a lever component the path cannot see near 0 with a small σ, which would
//! read as a measurement: the audit states z only when the body's up axis tilts by
//! [`MIN_TILT_RAD`] or more over the mission (a planar mission never tilts: z is `null`), and x
//! and y only when the heading turns by [`MIN_TURN_RAD`] or more within the fit's windows (each
//! window's own rotation absorbs a lever that keeps one heading). A
//! forward lever and Δt are told apart only by changes of speed: at a constant speed v a sensor Δx
//! ahead is a sensor Δx/v early; the pose fit says when they are inseparable, and so does the
//! audit (`forward_separable: false`).
//!
//! **Positions only** (a prism, a GNSS): lateral from the Drift Error's lever fit (L_est = s·(L_ref −
//! d·Δψ)), forward from the lead of curvature over speed (`implied_lever_arm_m` of the time offset,
//! when `auto` found one), vertical unknown. Separable when the speed method was confident (speed is
//! blind to a forward lever; a path without speed changes gives it nothing to lock on).
//!
//! On six simulated multi-source missions the pose fit's forward lever came within 5.5 mm of the
//! truth (median 1.0 mm) where a separate fit (per-window similarities with the source interpolated
//! linearly between its samples) was up to 31.5 mm off with a σ of 1 mm: interpolating between two
//! noisy samples averages their noise, so such a fit prefers stamps between samples and its Δt
//! shifts by a few milliseconds, the forward lever with it (docs/evidence.md, "Mission audits").

use nalgebra::Vector3;

use super::report::{LeverFit, LeverMethod};
use crate::report::json::{EstimateReport, TimeOffsetReport};
use crate::trajectory::Trajectory;

/// The vertical lever is observable only when the body tilts: the RMS angle of its up axis about
/// its mean must reach this (2°; a 0.3 m vertical lever then moves 1 cm, above the noise).
pub const MIN_TILT_RAD: f64 = 0.035;
/// The horizontal lever is observable only when the heading turns within the fit's windows: the
/// RMS over windows of the heading's spread within each must reach this (2°, as for the tilt).
pub const MIN_TURN_RAD: f64 = 0.035;
/// A lever component beyond a robot's size is a fit that did not settle: not stated, metres.
pub const MAX_LEVER_M: f64 = 5.0;

/// The lever of a source with orientations from the time offset of its evaluation against the
/// reference, when the pose fit ran; `None` otherwise (the positions' lever is then the one to
/// state).
pub fn pose_lever(o: &TimeOffsetReport, src: &Trajectory) -> Option<LeverFit> {
    let lever = o.fitted_lever_m?;
    let sigma = o.fitted_lever_sigma_m;
    let tilts = tilt_rad(src) >= MIN_TILT_RAD;
    let window_s = o
        .profile_window_s
        .unwrap_or(crate::align::pose_fit::WINDOW_S);
    let turns = turn_rad(src, window_s) >= MIN_TURN_RAD;
    let stated = |k: usize| {
        lever[k].is_finite() && lever[k].abs() <= MAX_LEVER_M && if k < 2 { turns } else { tilts }
    };
    let lever_m = [0, 1, 2].map(|k| stated(k).then_some(lever[k]));
    let sigma_m = [0, 1, 2].map(|k| sigma.filter(|_| stated(k)).map(|s| s[k]));
    // Untested (the chosen model's fit did not converge) is not separable.
    let forward_separable = o.fitted_forward_separable == Some(true) && stated(0);
    let mut note = match o.profile_window_s {
        Some(w) if !o.profile.is_empty() => format!(
            "the evaluation's pose fit (its profile: {} windows of {w:.0} s), with Δt {:+.4} s",
            o.profile.len(),
            o.offset_s
        ),
        _ => format!("the evaluation's pose fit, with Δt {:+.4} s", o.offset_s),
    };
    if sigma.is_none() {
        note.push_str("; no σ (the chosen clock model's fit did not converge)");
    }
    if !turns {
        note.push_str(
            "; the path hardly turns within a window, so the horizontal lever is unknown",
        );
    }
    if !tilts {
        note.push_str("; the path never tilts, so the vertical lever is unknown");
    }
    match o.fitted_forward_separable {
        Some(false) => note.push_str(
            "; the speed hardly changes, so a forward lever cannot be told from Δt: a sensor Δx ahead looks Δx/v early",
        ),
        None => note.push_str("; whether a forward lever can be told from Δt was not tested"),
        Some(true) => {}
    }
    Some(LeverFit {
        method: LeverMethod::PoseFit,
        lever_m,
        sigma_m,
        dt_s: Some(o.offset_s),
        dt_sigma_s: o.sigma_s,
        forward_separable,
        windows: o.profile.len(),
        note,
    })
}

/// The spread of the body's up axis over the samples of `src`, radians (0 without orientations).
pub fn tilt_rad(src: &Trajectory) -> f64 {
    let Some(q) = src.orientations.as_deref() else {
        return 0.0;
    };
    let ups: Vec<Vector3<f64>> = q.iter().map(|r| r * Vector3::z()).collect();
    let n = ups.len().max(1) as f64;
    let mean_up = ups.iter().sum::<Vector3<f64>>() / n;
    (ups.iter()
        .map(|u| (u - mean_up).norm_squared())
        .sum::<f64>()
        / n)
        .sqrt()
}

/// The heading's spread within windows of `window_s` over the samples of `src`: the RMS over
/// windows of each window's RMS spread of the body's forward axis (projected on the horizontal)
/// about its mean, radians (0 without orientations).
pub fn turn_rad(src: &Trajectory, window_s: f64) -> f64 {
    let Some(q) = src.orientations.as_deref() else {
        return 0.0;
    };
    let (Some(&t0), true) = (src.stamps_ns.first(), window_s > 0.0) else {
        return 0.0;
    };
    let window = |t: i64| ((t - t0) as f64 * 1e-9 / window_s) as usize;
    let (mut total, mut windows) = (0.0, 0usize);
    let mut start = 0;
    while start < q.len() {
        let w = window(src.stamps_ns[start]);
        let end = start
            + src.stamps_ns[start..]
                .iter()
                .take_while(|&&t| window(t) == w)
                .count();
        let heads: Vec<Vector3<f64>> = q[start..end]
            .iter()
            .map(|r| {
                let f = r * Vector3::x();
                Vector3::new(f.x, f.y, 0.0)
                    .try_normalize(1e-9)
                    .unwrap_or_else(Vector3::zeros)
            })
            .collect();
        let n = heads.len() as f64;
        let mean = heads.iter().sum::<Vector3<f64>>() / n;
        total += heads.iter().map(|h| (h - mean).norm_squared()).sum::<f64>() / n;
        windows += 1;
        start = end;
    }
    (total / windows.max(1) as f64).sqrt()
}

/// The lever from positions alone, from a source's evaluation against the reference.
pub fn positions_lever(e: &EstimateReport) -> LeverFit {
    let lateral = e.drift_error.first().and_then(|d| d.lateral_lever_m);
    let forward = e.time_offset.implied_lever_arm_m;
    let speed_ok = e.time_offset.methods.iter().any(|m| {
        m.method == crate::align::time_offset::OffsetMethod::Speed
            && m.status == crate::report::json::MethodStatus::Ok
    });
    let mut note = String::from("from positions alone: ");
    note.push_str(match lateral {
        Some(_) => "lateral from the Drift Error's lever fit",
        None => "no lateral lever (no Drift Error lever fit)",
    });
    note.push_str(match forward {
        Some(_) => ", forward from the lead of curvature over speed",
        None => ", no forward lever seen (curvature and speed agree)",
    });
    note.push_str("; the vertical one needs orientation");
    if !speed_ok {
        note.push_str(
            "; the speed method was not confident, so a forward lever cannot be told from Δt",
        );
    }
    LeverFit {
        method: LeverMethod::Positions,
        lever_m: [forward.or(Some(0.0).filter(|_| speed_ok)), lateral, None],
        sigma_m: [None, None, None],
        dt_s: None,
        dt_sigma_s: None,
        forward_separable: speed_ok,
        windows: 0,
        note,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// A source whose body rolls by ±`roll_rad` (sinusoidally) while it turns.
    fn rolling(roll_rad: f64) -> Trajectory {
        let mut t = Trajectory::new(true);
        for k in 0..1000 {
            let a = k as f64 * 0.01;
            let q = UnitQuaternion::from_euler_angles(roll_rad * (3.0 * a).sin(), 0.0, a);
            t.push(
                k * 100_000_000,
                Vector3::new(a.cos(), a.sin(), 0.0),
                Some(q),
            );
        }
        t
    }

    fn report(lever: [f64; 3], separable: bool) -> TimeOffsetReport {
        TimeOffsetReport {
            fitted_lever_m: Some(lever),
            fitted_lever_sigma_m: Some([0.001, 0.002, 0.003]),
            fitted_forward_separable: Some(separable),
            offset_s: 0.25,
            sigma_s: Some(0.001),
            ..TimeOffsetReport::default()
        }
    }

    #[test]
    fn a_planar_path_states_no_vertical_lever() {
        let f = pose_lever(&report([0.4, -0.25, 0.02], true), &rolling(0.0)).unwrap();
        assert_eq!(f.lever_m, [Some(0.4), Some(-0.25), None]);
        assert_eq!(f.sigma_m, [Some(0.001), Some(0.002), None]);
        assert_eq!(f.dt_s, Some(0.25));
        assert!(f.forward_separable);
        assert!(f.note.contains("never tilts"), "{}", f.note);
    }

    #[test]
    fn a_tilting_path_states_the_vertical_lever() {
        // ±5° of roll: an RMS tilt of about 3.5°.
        let src = rolling(5f64.to_radians());
        assert!(tilt_rad(&src) > MIN_TILT_RAD, "{}", tilt_rad(&src));
        let f = pose_lever(&report([0.4, -0.25, 0.3], true), &src).unwrap();
        assert_eq!(f.lever_m, [Some(0.4), Some(-0.25), Some(0.3)]);
    }

    #[test]
    fn a_straight_path_states_no_horizontal_lever() {
        let mut src = Trajectory::new(true);
        for k in 0..1000 {
            let q = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3);
            src.push(
                k * 100_000_000,
                Vector3::new(k as f64 * 0.1, 0.0, 0.0),
                Some(q),
            );
        }
        assert!(turn_rad(&src, 20.0) < 1e-9);
        let f = pose_lever(&report([0.4, -0.25, 0.0], true), &src).unwrap();
        assert_eq!(f.lever_m, [None, None, None]);
        assert!(!f.forward_separable);
        assert!(f.note.contains("hardly turns"), "{}", f.note);
    }

    #[test]
    fn an_inseparable_forward_lever_is_said() {
        let f = pose_lever(&report([0.4, 0.0, 0.0], false), &rolling(0.0)).unwrap();
        assert!(!f.forward_separable);
        assert!(f.note.contains("cannot be told"), "{}", f.note);
        // A lever beyond a robot's size is not stated.
        let f = pose_lever(&report([7.0, 0.1, 0.0], true), &rolling(0.0)).unwrap();
        assert_eq!(f.lever_m[0], None);
        assert!(!f.forward_separable);
    }

    #[test]
    fn an_untested_forward_lever_is_not_called_separable() {
        let o = TimeOffsetReport {
            fitted_forward_separable: None,
            fitted_lever_sigma_m: None,
            ..report([0.4, 0.0, 0.0], true)
        };
        let f = pose_lever(&o, &rolling(0.0)).unwrap();
        assert!(!f.forward_separable);
        assert_eq!(f.sigma_m, [None, None, None]);
        assert!(f.note.contains("not tested"), "{}", f.note);
    }

    #[test]
    fn without_a_pose_fit_there_is_no_pose_lever() {
        assert!(pose_lever(&TimeOffsetReport::default(), &rolling(0.0)).is_none());
    }
}

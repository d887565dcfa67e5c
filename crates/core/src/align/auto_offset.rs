//! `--offset-method auto`: run every method, apply only an answer that is confident and consistent.
//!
//! What each method can and cannot see (measured on simulated missions with a known offset):
//! * `speed` (2 s window, mean-removed) is immune to a lever arm to first order, but blind at constant
//!   speed; where it is confident it was within ~10 ms.
//! * `signed-curvature` sees turns, left and right apart, but a sensor mounted Δx ahead of the other
//!   sees every curve Δx/v earlier: 0.2 m at 0.3 m/s biases Δt by 0.5 s at an NCC of 0.99.
//! * `curvature` (unsigned, the paper's) correlates positively even on pure noise (raw NCC ≈ 0.85)
//!   and carries the same lead; it is reported, never applied by `auto`.
//!
//! The rule: a confident speed answer is applied. When signed curvature is confident too and they
//! disagree by more than [`AGREE_S`] and [`MIN_LEVER_M`]/v, the gap is read as the lead of a longitudinal lever arm
//! Δx = v·(Δt_curv − Δt_speed) (v: the reference's mean speed while moving) and reported as a
//! `lever_arm_suspected` warning; a gap no plausible lever arm explains (|Δx| > [`MAX_LEVER_M`])
//! makes the answer `weak`. Before a disagreement is judged, signed curvature is measured again with
//! the reference's stands left out (`crate::align::still`): a turn in place seen by a sensor beside
//! the reference point otherwise fakes a lead of several tenths of a second. Signed curvature alone
//! is applied with a `lever_arm_unchecked` warning (speed cannot rule the lead out). Nothing
//! confident: `weak` (the evaluation then starts the pose fit from each answer, where the estimate
//! has orientations, and applies it where the positions decide: `pose_rescued` in the `trajdrift`
//! crate's `eval`).

use nalgebra::Vector3;

use crate::align::auto_params::moving_speed;
use crate::align::still::still_intervals;
use crate::align::time_offset::{
    estimate_time_offset_cached, OffsetEstimate, OffsetMethod, OffsetParams, OffsetStatus, Pair,
    SignalCache,
};
use crate::error::Result;
use crate::sources::Warning;

/// The methods `auto` runs, in the order they are reported.
pub const AUTO_METHODS: [OffsetMethod; 3] = [
    OffsetMethod::Speed,
    OffsetMethod::SignedCurvature,
    OffsetMethod::Curvature,
];
/// Speed and signed curvature agree when within this, seconds (both are good to ~10–20 ms; a 5 cm
/// lever arm at 1.5 m/s is 33 ms).
pub const AGREE_S: f64 = 0.05;
/// A gap whose implied lever arm is below this is taken as agreement too, metres (at a legged robot's
/// 0.3 m/s the two methods' own errors of a few tens of ms are a few cm of "lever").
pub const MIN_LEVER_M: f64 = 0.1;
/// The largest longitudinal lever arm taken as an explanation of a disagreement, metres.
pub const MAX_LEVER_M: f64 = 2.0;

/// How the methods' answers were combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Speed and signed curvature are confident and agree: speed applied.
    Agree,
    /// They disagree by a plausible lever-arm lead: speed applied, warning.
    LeverArm,
    /// They disagree by more than any lever arm explains: weak.
    Contradiction,
    /// Only speed is confident: applied.
    SpeedOnly,
    /// Only signed curvature is confident: applied, with a warning.
    CurvatureOnly,
    /// Nothing is confident: weak.
    Nothing,
}

/// The combined decision (pure; see [`decide`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    pub verdict: Verdict,
    /// The method whose answer is applied (`None`: weak).
    pub applied: Option<OffsetMethod>,
    /// Why, in one sentence.
    pub reason: String,
    /// v·(Δt_curv − Δt_speed) when both are confident and disagree, metres.
    pub implied_lever_arm_m: Option<f64>,
}

/// Combines a speed and a signed-curvature answer (each `None` when it failed). `mean_speed_mps` is
/// the reference's mean speed while moving.
pub fn decide(
    speed: Option<&OffsetEstimate>,
    signed: Option<&OffsetEstimate>,
    mean_speed_mps: Option<f64>,
) -> Decision {
    let ok = |o: Option<&OffsetEstimate>| o.filter(|o| o.status == OffsetStatus::Ok).copied();
    match (ok(speed), ok(signed)) {
        (Some(s), Some(c)) => {
            let gap = c.offset_s - s.offset_s;
            let small_lever = mean_speed_mps.is_some_and(|v| (v * gap).abs() <= MIN_LEVER_M);
            if gap.abs() <= AGREE_S || small_lever {
                return Decision {
                    verdict: Verdict::Agree,
                    applied: Some(OffsetMethod::Speed),
                    reason: format!(
                        "speed and signed-curvature agree ({:+.0} ms apart); speed applied (immune to a lever arm)",
                        gap * 1e3
                    ),
                    implied_lever_arm_m: None,
                };
            }
            let lever = mean_speed_mps.map(|v| v * gap);
            match lever {
                Some(l) if l.abs() <= MAX_LEVER_M => Decision {
                    verdict: Verdict::LeverArm,
                    applied: Some(OffsetMethod::Speed),
                    reason: format!(
                        "signed-curvature leads speed by {:+.3} s, the lead of a sensor mounted {:+.2} m ahead of the other along the direction of travel at the mean {:.2} m/s; speed applied (immune to that lead)",
                        gap,
                        l,
                        mean_speed_mps.unwrap_or(0.0)
                    ),
                    implied_lever_arm_m: Some(l),
                },
                _ => Decision {
                    verdict: Verdict::Contradiction,
                    applied: None,
                    reason: format!(
                        "speed ({:+.3} s) and signed-curvature ({:+.3} s) are both confident but {:.3} s apart, more than any lever arm explains; no offset applied",
                        s.offset_s,
                        c.offset_s,
                        gap.abs()
                    ),
                    implied_lever_arm_m: lever,
                },
            }
        }
        (Some(_), None) => Decision {
            verdict: Verdict::SpeedOnly,
            applied: Some(OffsetMethod::Speed),
            reason: "speed is confident, signed-curvature is not; speed applied".into(),
            implied_lever_arm_m: None,
        },
        (None, Some(_)) => Decision {
            verdict: Verdict::CurvatureOnly,
            applied: Some(OffsetMethod::SignedCurvature),
            reason: format!(
                "only signed-curvature is confident; applied, but it is early by Δx/v for a sensor mounted Δx ahead of the other ({:.0} ms per 0.1 m here) and speed cannot check it",
                mean_speed_mps.map_or(f64::NAN, |v| 100.0 / v)
            ),
            implied_lever_arm_m: None,
        },
        (None, None) => Decision {
            verdict: Verdict::Nothing,
            applied: None,
            reason: "no method found a confident peak (constant speed and no turns?); no offset applied".into(),
            implied_lever_arm_m: None,
        },
    }
}

/// The result of the `auto` search.
#[derive(Debug)]
pub struct AutoOffset {
    /// The applied answer; when nothing is applied, the most confident one with status `weak`.
    pub estimate: OffsetEstimate,
    /// Every method's answer, in [`AUTO_METHODS`] order.
    pub runs: Vec<(OffsetMethod, Result<OffsetEstimate>)>,
    pub decision: Decision,
    /// The reference's mean speed while moving, m/s.
    pub mean_speed_mps: Option<f64>,
    /// Warnings the user must see (`lever_arm_suspected`, `lever_arm_unchecked`).
    pub warnings: Vec<Warning>,
}

/// Runs [`AUTO_METHODS`] and combines them (see the module doc). Errors only when every method
/// failed (the first method's error is returned).
pub fn auto_time_offset(
    ref_t: &[f64],
    ref_p: &[Vector3<f64>],
    est_t: &[f64],
    est_p: &[Vector3<f64>],
    params: &OffsetParams,
) -> Result<AutoOffset> {
    let cache = SignalCache::default();
    auto_time_offset_of(&Pair::new((ref_t, ref_p), (est_t, est_p), &cache), params)
}

/// `--offset-refine`: whether `auto` refines the signal searches' answer by the pose fit (when the
/// estimate has orientations; see [`crate::align::pose_model`]), or keeps it (`none`: the paper's
/// signals alone, and the estimate's orientations not read).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OffsetRefine {
    /// The pose fit refines the answer, the profile and the clock model.
    #[default]
    Pose,
    /// The signal searches' answer stands.
    None,
}

/// [`auto_time_offset`] over the signals of `pair` (each computed once, kept for the profile).
pub fn auto_time_offset_of(pair: &Pair<'_>, params: &OffsetParams) -> Result<AutoOffset> {
    use rayon::prelude::*;
    let (ref_t, ref_p) = pair.reference;
    let runs: Vec<(OffsetMethod, Result<OffsetEstimate>)> = AUTO_METHODS
        .par_iter()
        .map(|&m| (m, estimate_time_offset_cached(m, pair, params, (&[], &[]))))
        .collect();
    let gap = params.max_gap_s.unwrap_or(params.curvature.dt_max_s);
    let mean_speed_mps = moving_speed(ref_t, ref_p, gap).map(|m| m.0);
    let get = |m: OffsetMethod| {
        runs.iter()
            .find(|(k, _)| *k == m)
            .and_then(|(_, r)| r.as_ref().ok())
    };
    let ok = |o: Option<&OffsetEstimate>| o.filter(|o| o.status == OffsetStatus::Ok).copied();
    let (speed, mut signed) = (
        ok(get(OffsetMethod::Speed)),
        ok(get(OffsetMethod::SignedCurvature)),
    );
    // Before a disagreement is read as a lever arm: the reference's stands (turns in place) left out
    // of the signed curvature, the estimate's at the speed answer (see `crate::align::still`).
    let stands_left_out = without_stands(pair, params, (speed, signed), mean_speed_mps, gap);
    if let Some((_, masked)) = &stands_left_out {
        signed = (masked.status == OffsetStatus::Ok).then_some(*masked);
    }
    let mut decision = decide(speed.as_ref(), signed.as_ref(), mean_speed_mps);
    if let (Some((n, masked)), Some(plain)) =
        (stands_left_out, ok(get(OffsetMethod::SignedCurvature)))
    {
        decision.reason = format!(
            "{} (signed-curvature {:+.3} s over the whole mission, {:+.3} s without the reference's {n} stand(s))",
            decision.reason, plain.offset_s, masked.offset_s
        );
    }
    let estimate = match decision.applied.and_then(get) {
        Some(o) => *o,
        None => {
            let best = runs
                .iter()
                .filter_map(|(_, r)| r.as_ref().ok())
                .max_by(|a, b| a.confidence.total_cmp(&b.confidence))
                .copied();
            match best {
                Some(o) => OffsetEstimate {
                    status: OffsetStatus::Weak,
                    ..o
                },
                None => {
                    // Every run failed: report the first method's error.
                    let mut runs = runs.into_iter();
                    return match runs.next() {
                        Some((_, Err(e))) => Err(e),
                        _ => Err(crate::error::Error::InvalidArgument(
                            "time offset: no method ran".into(),
                        )),
                    };
                }
            }
        }
    };
    let warnings = verdict_warnings(&decision);
    Ok(AutoOffset {
        estimate,
        runs,
        decision,
        mean_speed_mps,
        warnings,
    })
}

/// The signed-curvature estimate with the reference's stands (turns in place) left out, when it
/// disagrees with the speed estimate: `(number of stands, the masked estimate)`; `None` when
/// they agree, a signal is missing or the reference has no stand.
fn without_stands(
    pair: &Pair<'_>,
    params: &OffsetParams,
    (speed, signed): (Option<OffsetEstimate>, Option<OffsetEstimate>),
    mean_speed_mps: Option<f64>,
    gap: f64,
) -> Option<(usize, OffsetEstimate)> {
    let (s, c, v) = (speed?, signed?, mean_speed_mps?);
    if (c.offset_s - s.offset_s).abs() <= AGREE_S {
        return None;
    }
    let (ref_t, ref_p) = pair.reference;
    let on_ref = still_intervals(ref_t, ref_p, gap, params.curvature.eps_m / v);
    if on_ref.is_empty() {
        return None;
    }
    let on_est: Vec<(f64, f64)> = on_ref
        .iter()
        .map(|&(a, b)| (a - s.offset_s, b - s.offset_s))
        .collect();
    let masked = estimate_time_offset_cached(
        OffsetMethod::SignedCurvature,
        pair,
        params,
        (&on_ref, &on_est),
    )
    .ok()?;
    Some((on_ref.len(), masked))
}

/// The warnings a verdict carries: a suspected lever arm, or a lever arm curvature alone cannot check.
fn verdict_warnings(decision: &Decision) -> Vec<Warning> {
    let mut warnings = Vec::new();
    match decision.verdict {
        Verdict::LeverArm => warnings.push(Warning {
            code: crate::diag::WarningCode::LeverArmSuspected,
            message: format!(
                "time offset: {}. Measure the lever arm between the sensors",
                decision.reason
            ),
        }),
        Verdict::CurvatureOnly => warnings.push(Warning {
            code: crate::diag::WarningCode::LeverArmUnchecked,
            message: format!(
                "time offset: {}. Give --time-offset if the sensors are mounted apart along the direction of travel",
                decision.reason
            ),
        }),
        _ => {}
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    fn est(method: OffsetMethod, offset_s: f64, ok: bool) -> OffsetEstimate {
        OffsetEstimate {
            method,
            offset_s,
            correlation: 0.9,
            confidence: if ok { 0.9 } else { 0.2 },
            status: if ok {
                OffsetStatus::Ok
            } else {
                OffsetStatus::Weak
            },
            overlap_fraction: 1.0,
            margin: 0.5,
            rival_offset_s: None,
            defined_fraction: 1.0,
            sigma_s: None,
        }
    }

    #[test]
    fn agreement_applies_speed() {
        let (s, c) = (
            est(OffsetMethod::Speed, 0.10, true),
            est(OffsetMethod::SignedCurvature, 0.12, true),
        );
        let d = decide(Some(&s), Some(&c), Some(1.5));
        assert_eq!(d.verdict, Verdict::Agree);
        assert_eq!(d.applied, Some(OffsetMethod::Speed));
    }

    #[test]
    fn a_lead_is_read_as_a_lever_arm_and_speed_is_applied() {
        // 0.3 m ahead at 1.5 m/s: curvature 0.2 s off.
        let (s, c) = (
            est(OffsetMethod::Speed, 0.10, true),
            est(OffsetMethod::SignedCurvature, 0.30, true),
        );
        let d = decide(Some(&s), Some(&c), Some(1.5));
        assert_eq!(d.verdict, Verdict::LeverArm);
        assert_eq!(d.applied, Some(OffsetMethod::Speed));
        assert!((d.implied_lever_arm_m.unwrap() - 0.3).abs() < 1e-9);
    }

    #[test]
    fn a_contradiction_applies_nothing() {
        let (s, c) = (
            est(OffsetMethod::Speed, 0.10, true),
            est(OffsetMethod::SignedCurvature, 5.0, true),
        );
        let d = decide(Some(&s), Some(&c), Some(1.5));
        assert_eq!(d.verdict, Verdict::Contradiction);
        assert_eq!(d.applied, None);
        // Without a speed to convert the gap, it is no lever arm either.
        let d = decide(Some(&s), Some(&c), None);
        assert_eq!(d.applied, None);
    }

    #[test]
    fn single_and_no_confident_answers() {
        let s = est(OffsetMethod::Speed, 0.1, true);
        let sw = est(OffsetMethod::Speed, 0.1, false);
        let c = est(OffsetMethod::SignedCurvature, 0.2, true);
        let cw = est(OffsetMethod::SignedCurvature, 0.2, false);
        assert_eq!(
            decide(Some(&s), Some(&cw), Some(1.0)).verdict,
            Verdict::SpeedOnly
        );
        assert_eq!(
            decide(Some(&s), None, Some(1.0)).verdict,
            Verdict::SpeedOnly
        );
        let d = decide(Some(&sw), Some(&c), Some(1.0));
        assert_eq!(d.verdict, Verdict::CurvatureOnly);
        assert_eq!(d.applied, Some(OffsetMethod::SignedCurvature));
        let d = decide(Some(&sw), Some(&cw), Some(1.0));
        assert_eq!((d.verdict, d.applied), (Verdict::Nothing, None));
        assert_eq!(decide(None, None, None).applied, None);
    }
}

use nalgebra::{DMatrix, Vector3};

use super::lead::{
    lead_searched, paired_t, referee_length_s, undecided_reach_s, within_lead_lever, Lead, LeadFit,
};
use super::sigma::set_parameters;
use super::*;
use crate::align::clock_model::{ClockModel, ClockSegment, OffsetModel};
use crate::align::offset_profile::{OffsetProfile, ProfileWindow};
use crate::align::pose_fit::{ClockShape, PoseFit};
use crate::align::time_offset::OffsetMethod;

/// Four disjoint 20 s windows at 10, 30, 50, 70 s, each `offset(t)` ± 2 ms.
fn profile(offset: impl Fn(f64) -> f64) -> OffsetProfile {
    OffsetProfile {
        method: OffsetMethod::Pose,
        window_s: 20.0,
        step_s: 20.0,
        sigma_scale: 1.0,
        windows: [10.0, 30.0, 50.0, 70.0]
            .map(|t| ProfileWindow {
                t,
                offset_s: offset(t),
                sigma_s: 0.002,
                correlation: 1.0,
                usable: true,
            })
            .to_vec(),
    }
}

/// A converged final fit with parameters `theta` and their σ `sigma`.
fn fit(shape: ClockShape, theta: Vec<f64>, sigma: Vec<f64>) -> PoseFit {
    let n = theta.len();
    PoseFit {
        shape,
        theta,
        lever_m: Vector3::zeros(),
        theta_jackknife_sigma: sigma.clone(),
        theta_formal_sigma: vec![0.0; n],
        theta_sigma: sigma,
        lever_sigma_m: None,
        covariance: DMatrix::zeros(n, n),
        variance_inflation: vec![1.0; n],
        windows: Vec::new(),
        outliers: Vec::new(),
        rms_m: Vec::new(),
        scale: 1.0,
        jacobian_scale: 1.0,
        iterations: 1,
        converged: true,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn a_step_is_resolved_only_beyond_three_sigma_of_the_difference_of_its_sides() {
    let two = |d: f64, var: f64, cov: f64| {
        let mut f = fit(
            ClockShape::Piecewise {
                changes: vec![100.0],
            },
            vec![0.2, 0.2 + d],
            vec![var.sqrt(); 2],
        );
        f.covariance = DMatrix::from_row_slice(2, 2, &[var, cov, cov, var]);
        f
    };
    // 6 ms under σ 14 ms on each side, uncorrelated: not a step.
    assert!(!steps_resolved(&two(0.006, 0.014f64.powi(2), 0.0)));
    // 100 ms: a step.
    assert!(steps_resolved(&two(0.1, 0.014f64.powi(2), 0.0)));
    // Sides that share most of their error (the lever's, which moves both alike): with 96 % of
    // the variance shared the difference is known to 4.0 ms, and 6 ms is within 3σ of it;
    // with 98 %, to 2.8 ms, and 10 ms is beyond.
    assert!(!steps_resolved(&two(
        0.006,
        0.014f64.powi(2),
        0.96 * 0.014f64.powi(2)
    )));
    assert!(steps_resolved(&two(
        0.010,
        0.014f64.powi(2),
        0.98 * 0.014f64.powi(2)
    )));
    // One segment: nothing to resolve.
    let one = fit(ClockShape::Constant, vec![0.2], vec![0.01]);
    assert!(steps_resolved(&one));
}

#[test]
fn a_profile_of_few_of_the_fits_windows_speaks_for_all_of_them() {
    let p = profile(|_| 0.1);
    let ms = |v: f64| v * 1e-3;
    let over = |n: usize| {
        let mut f = fit(ClockShape::Constant, vec![0.1], vec![ms(0.3)]);
        f.windows = (0..n)
            .map(|k| pose_fit::Window {
                range: 0..0,
                t_start: 20.0 * k as f64,
                t_end: 20.0 * (k + 1) as f64,
            })
            .collect();
        f
    };
    // The fit over the profile's four windows of 20 s: they combine to 1 ms, as before.
    let mut m = ClockModel::constant(0.0, 0.0, String::new());
    let parts = set_parameters(&mut m, &over(4), &p, 0.0, Cuts::NONE).unwrap();
    assert!(close(parts.windows_s.unwrap(), ms(1.0)), "{parts:?}");
    // The fit over sixteen such windows, of which the profile kept four: their 1 ms is the
    // error of a four-window answer, the fit's over sixteen is √(4/16) of it; pooled with the
    // jackknife, √((0.3² + 0.5²)/2) ms.
    let mut m = ClockModel::constant(0.0, 0.0, String::new());
    let parts = set_parameters(&mut m, &over(16), &p, 0.0, Cuts::NONE).unwrap();
    assert!(close(parts.windows_s.unwrap(), ms(0.5)), "{parts:?}");
    assert!(close(m.sigma_s, ms(0.17f64.sqrt())), "{m:?}");
}

#[test]
fn an_offsets_sigma_pools_the_jackknife_with_the_windows_at_least_the_formal() {
    let p = profile(|_| 0.1);
    let constant = || ClockModel::constant(0.0, 0.0, String::new());
    let ms = |v: f64| v * 1e-3;
    // The four windows combine to 2 ms / √4 = 1 ms: a jackknife of 0.3 ms is pooled with it,
    // √((0.3² + 1²)/2) ms.
    let mut m = constant();
    set_parameters(
        &mut m,
        &fit(ClockShape::Constant, vec![0.1], vec![ms(0.3)]),
        &p,
        0.0,
        Cuts::NONE,
    );
    assert!(
        close(m.offset_s, 0.1) && close(m.sigma_s, ms(0.545f64.sqrt())),
        "{m:?}"
    );
    // A jackknife wider than the windows is pooled the same way: √((5² + 1²)/2) ms.
    let mut m = constant();
    set_parameters(
        &mut m,
        &fit(ClockShape::Constant, vec![0.1], vec![ms(5.0)]),
        &p,
        0.0,
        Cuts::NONE,
    );
    assert!(close(m.sigma_s, ms(13f64.sqrt())), "{m:?}");
    // The formal σ stays the floor.
    let mut sure = fit(ClockShape::Constant, vec![0.1], vec![ms(2.0)]);
    sure.theta_jackknife_sigma = vec![ms(0.3)];
    sure.theta_formal_sigma = vec![ms(2.0)];
    let mut m = constant();
    let parts =
        set_parameters(&mut m, &sure, &p, 0.0, Cuts::NONE).expect("a constant's σ has its parts");
    assert!(close(m.sigma_s, ms(2.0)), "{m:?}");
    // The report's `sigma_parts` say so.
    assert_eq!(parts.combined, SigmaCombination::Pooled);
    assert!(close(parts.jackknife_s, ms(0.3)) && close(parts.formal_s, ms(2.0)));
    assert!(close(parts.windows_s.unwrap(), ms(1.0)) && parts.hidden_drift_s == 0.0);
    // It is the jackknife that is pooled, not the fit's σ already raised to the formal one:
    // jackknife 0.3 ms, formal 0.5 ms, windows 1 ms give √((0.3² + 1²)/2) ms.
    let mut raised = fit(ClockShape::Constant, vec![0.1], vec![ms(0.5)]);
    raised.theta_jackknife_sigma = vec![ms(0.3)];
    raised.theta_formal_sigma = vec![ms(0.5)];
    let mut m = constant();
    set_parameters(&mut m, &raised, &p, 0.0, Cuts::NONE);
    assert!(close(m.sigma_s, ms(0.545f64.sqrt())), "{m:?}");
    // The mean over tilings removes the cuts' part in quadrature (√(0.545 − 0.2²) ms), never
    // below the formal σ (0.6 ms, with 0.45 ms removed).
    let cuts = |removed_s: f64| Cuts {
        removed_s,
        tilings: 4,
    };
    let mut m = constant();
    let parts = set_parameters(&mut m, &raised, &p, 0.0, cuts(ms(0.2))).unwrap();
    assert!(
        close(m.sigma_s, ms(0.505f64.sqrt())) && close(parts.cuts_s, ms(0.2)),
        "{m:?}"
    );
    let mut m = constant();
    let mut floored = raised.clone();
    floored.theta_formal_sigma = vec![ms(0.6)];
    set_parameters(&mut m, &floored, &p, 0.0, cuts(ms(0.45)));
    assert!(close(m.sigma_s, ms(0.6)), "{m:?}");
    // A spread of the tilings as large as σ itself is not removed: 0.7 ms of 0.74 ms.
    let mut m = constant();
    let parts = set_parameters(&mut m, &raised, &p, 0.0, cuts(ms(0.7))).unwrap();
    assert!(
        close(m.sigma_s, ms(0.545f64.sqrt())) && parts.cuts_s == 0.0,
        "{m:?}"
    );
    // A jackknife that saw no spread is no estimate: the larger of the fit's σ and the windows'.
    let mut flat = fit(ClockShape::Constant, vec![0.1], vec![ms(0.5)]);
    flat.theta_jackknife_sigma = vec![0.0];
    let mut m = constant();
    let parts = set_parameters(&mut m, &flat, &p, 0.0, Cuts::NONE).unwrap();
    assert!(close(m.sigma_s, ms(1.0)) && parts.combined == SigmaCombination::Larger);
    // Windows scattering ±4 ms about the offset with σ 2 ms: theirs grows by the Birge ratio
    // √(χ²/dof) = √(4·4/3) before the pooling.
    let scattered = profile(|t| {
        if t < 20.0 || (40.0..60.0).contains(&t) {
            0.104
        } else {
            0.096
        }
    });
    let mut m = constant();
    set_parameters(
        &mut m,
        &fit(ClockShape::Constant, vec![0.1], vec![ms(0.3)]),
        &scattered,
        0.0,
        Cuts::NONE,
    );
    let windows_s = ms(1.0) * (16.0f64 / 3.0).sqrt();
    let expected = ((ms(0.3).powi(2) + windows_s * windows_s) / 2.0).sqrt();
    assert!(close(m.sigma_s, expected), "{m:?}");
}

#[test]
fn the_windows_part_carries_the_share_of_sigma_the_fitted_lever_adds() {
    let p = profile(|_| 0.1);
    let ms = |v: f64| v * 1e-3;
    // A fit whose formal σ of 2 ms is four times the variance it would have with the lever
    // held: the lever's freedom adds 2·√(1 − 1/4) = √3 ms, which the windows (1 ms, lever held)
    // cannot see. Pooled with the jackknife's 3 ms: √((3² + 1² + 3)/2) = √6.5 ms.
    let mut lever_free = fit(ClockShape::Constant, vec![0.1], vec![ms(3.0)]);
    lever_free.theta_formal_sigma = vec![ms(2.0)];
    lever_free.variance_inflation = vec![4.0];
    assert!(close(lever_free.lever_share_s(0), ms(3f64.sqrt())));
    let mut m = ClockModel::constant(0.0, 0.0, String::new());
    let parts = set_parameters(&mut m, &lever_free, &p, 0.0, Cuts::NONE).unwrap();
    assert!(close(m.sigma_s, ms(6.5f64.sqrt())), "{m:?}");
    assert!(close(parts.lever_s, ms(3f64.sqrt())));
    assert!(close(parts.windows_s.unwrap(), ms(1.0)));
    // Without a lever (inflation 1) nothing is added: √((3² + 1²)/2) ms.
    lever_free.variance_inflation = vec![1.0];
    let mut m = ClockModel::constant(0.0, 0.0, String::new());
    let parts = set_parameters(&mut m, &lever_free, &p, 0.0, Cuts::NONE).unwrap();
    assert!(
        close(m.sigma_s, ms(5f64.sqrt())) && parts.lever_s == 0.0,
        "{m:?}"
    );
}

#[test]
fn a_segment_over_fewer_than_three_windows_keeps_the_larger() {
    // Two segments, 0–60 s (windows at 10, 30, 50 s) and 60–80 s (the window at 70 s).
    let p = profile(|_| 0.1);
    let segment = |t_start: f64, t_end: f64| ClockSegment {
        t_start,
        t_end,
        offset_s: 0.0,
        sigma_s: 0.0,
    };
    let mut m = ClockModel {
        model: OffsetModel::Piecewise,
        segments: vec![segment(0.0, 60.0), segment(60.0, 80.0)],
        ..ClockModel::constant(0.0, 0.0, String::new())
    };
    let shape = ClockShape::Piecewise {
        changes: vec![60.0],
    };
    let parts = set_parameters(
        &mut m,
        &fit(shape, vec![0.1, 0.2], vec![3e-4, 3e-4]),
        &p,
        0.0,
        Cuts::NONE,
    )
    .expect("the headline segment's parts");
    // Three windows of 2 ms: 2/√3 ms, pooled with the jackknife's 0.3 ms.
    let three_s = 0.002 / 3f64.sqrt();
    let pooled_s = ((3e-4f64.powi(2) + three_s * three_s) / 2.0).sqrt();
    assert!(close(m.segments[0].sigma_s, pooled_s), "{m:?}");
    assert_eq!(parts.combined, SigmaCombination::Pooled);
    assert!(
        close(m.sigma_s, pooled_s),
        "the longest segment is the headline"
    );
    // One window: its 2 ms, the larger.
    assert!(close(m.segments[1].sigma_s, 0.002), "{m:?}");
}

#[test]
fn a_drift_below_the_resolution_widens_the_constant_only_beyond_twice_its_sigma() {
    // Four windows at 10–70 s: their times spread by √500 s about their mean (equal σ).
    let p = profile(|_| 0.1);
    let spread_s = 500f64.sqrt();
    let constant = |d: f64| ClockModel {
        drift_ppm: Some(d),
        drift_sigma_ppm: Some(10.0),
        ..ClockModel::constant(0.0, 0.0, String::new())
    };
    let fitted = fit(ClockShape::Constant, vec![0.1], vec![0.005]);
    // The jackknife's 5 ms pooled with the windows' 1 ms.
    let pooled_s = 13f64.sqrt() * 1e-3;
    // 15 ppm measured with σ 10 ppm: what a constant clock shows by chance; σ stays the pooled.
    let mut m = constant(15.0);
    set_parameters(&mut m, &fitted, &p, 0.0, Cuts::NONE);
    assert!(close(m.sigma_s, pooled_s), "{m:?}");
    // 30 ppm, 3σ: the part beyond its noise, √(30² − 10²) ppm, over the windows' spread.
    let mut m = constant(-30.0);
    set_parameters(&mut m, &fitted, &p, 0.0, Cuts::NONE);
    let hidden_s = 800f64.sqrt() * 1e-6 * spread_s;
    assert!(
        close(m.sigma_s, (pooled_s.powi(2) + hidden_s * hidden_s).sqrt()),
        "{m:?}"
    );
}

#[test]
fn a_line_keeps_the_drifts_floor_and_states_it_in_ppm() {
    let p = profile(|t| 0.1 - 50e-6 * (t - 40.0));
    let mut m = ClockModel {
        model: OffsetModel::Linear,
        t_mid: 40.0,
        drift_ppm: Some(50.0),
        drift_sigma_ppm: Some(3.0),
        ..ClockModel::constant(0.1, 0.0, String::new())
    };
    let shape = ClockShape::Linear { t_mid: 40.0 };
    // θ₁ = −48·10⁻⁶ s/s is a clock running 48 ppm fast; its σ of 1 ppm is raised to the 3 ppm
    // `choose_model` left on the model, and the offset's 0.2 ms to the line's at t_mid (1 ms).
    set_parameters(
        &mut m,
        &fit(shape.clone(), vec![0.1, -48e-6], vec![2e-4, 1e-6]),
        &p,
        0.0,
        Cuts::NONE,
    );
    assert!(close(m.drift_ppm.unwrap(), 48.0));
    assert!(close(m.drift_sigma_ppm.unwrap(), 3.0));
    assert!(close(m.sigma_s, 0.001), "{m:?}");
    // A wider final fit stands.
    m.drift_sigma_ppm = Some(3.0);
    set_parameters(
        &mut m,
        &fit(shape, vec![0.1, -48e-6], vec![0.004, 5e-6]),
        &p,
        0.0,
        Cuts::NONE,
    );
    assert!(close(m.drift_sigma_ppm.unwrap(), 5.0) && close(m.sigma_s, 0.004));
}

#[test]
fn the_lead_search_questions_a_constant_and_a_step_or_a_drift_of_the_windows_own_not_a_forced_model(
) {
    assert!(lead_searched(OffsetModel::Constant, None));
    assert!(lead_searched(OffsetModel::Piecewise, None));
    assert!(lead_searched(
        OffsetModel::Constant,
        Some(OffsetModel::Constant)
    ));
    assert!(!lead_searched(
        OffsetModel::Piecewise,
        Some(OffsetModel::Piecewise)
    ));
    assert!(lead_searched(OffsetModel::Linear, None));
    assert!(!lead_searched(
        OffsetModel::Linear,
        Some(OffsetModel::Linear)
    ));
}

#[test]
fn a_lead_fit_needing_a_forward_lever_beyond_the_searchs_is_not_a_candidate() {
    let with_lever = |x: f64, sigma_x: Option<f64>| PoseFit {
        lever_m: Vector3::new(x, 0.3, -0.4),
        lever_sigma_m: sigma_x.map(|s| Vector3::new(s, 0.04, 0.4)),
        ..fit(ClockShape::Constant, vec![3.76], vec![0.04])
    };
    // A walking robot's fit 3.4 s off traded Δt for a forward lever of 0.86 ± 0.07 m.
    assert!(!within_lead_lever(&with_lever(-0.86, Some(0.07))));
    assert!(within_lead_lever(&with_lever(0.39, Some(0.01))));
    // Beyond the bound, but not by two of its σ: the data do not say it is.
    assert!(within_lead_lever(&with_lever(0.6, Some(0.1))));
    // Only the forward lever trades with Δt (the lateral and vertical ones do not count).
    assert!(within_lead_lever(&PoseFit {
        lever_m: Vector3::new(0.1, 0.9, 0.9),
        ..with_lever(0.1, Some(0.01))
    }));
    // Without a fitted lever's σ nothing rules the fit out.
    assert!(within_lead_lever(&with_lever(-0.86, None)));
}

#[test]
fn a_long_lever_fit_left_out_is_told_where_it_fits_the_windows_better() {
    // Residuals of 20 windows: `level` each, ± `wobble` alternately.
    let shifted = |level: f64, wobble: f64| -> Vec<Option<f64>> {
        (0..20)
            .map(|k| Some(level + if k % 2 == 0 { wobble } else { -wobble }))
            .collect()
    };
    let long = |theta: f64, forward_m: f64| PoseFit {
        lever_m: Vector3::new(forward_m, 0.0, 0.0),
        lever_sigma_m: Some(Vector3::new(0.01, 0.01, 0.05)),
        ..fit(ClockShape::Constant, vec![theta], vec![1e-3])
    };
    let lead = |beyond: Vec<(PoseFit, Vec<Option<f64>>)>| Lead {
        windows: Vec::new(),
        fits: Vec::new(),
        beyond: beyond
            .into_iter()
            .map(|(fit, residuals)| LeadFit {
                fit,
                residuals,
                from: None,
            })
            .collect(),
    };
    let reported = shifted(1.0, 0.01);
    // Worse than the reported fit in every window: nothing to tell.
    assert_eq!(
        lead(vec![(long(3.7, -0.86), shifted(1.2, 0.01))]).beyond_against(&reported),
        None
    );
    // Better: the best of those that are.
    let told = lead(vec![
        (long(3.7, -0.86), shifted(1.2, 0.01)),
        (long(-0.22, 0.71), shifted(0.9, 0.01)),
        (long(0.9, 0.66), shifted(0.99, 0.02)),
    ])
    .beyond_against(&reported);
    assert_eq!(
        told,
        Some(BeyondLever {
            offset_s: -0.22,
            forward_m: 0.71,
            forward_sigma_m: 0.01
        })
    );
    assert!(lead(Vec::new()).beyond_against(&reported).is_none());
}

#[test]
fn fits_along_the_valley_the_windows_cannot_tell_apart_widen_sigma() {
    let at = |theta: f64| fit(ClockShape::Constant, vec![theta], vec![1e-3]);
    // Twenty windows' residuals per point (mm²) of one fit, a wobble of ±0.1 about 1.
    let base: Vec<Option<f64>> = (0..20)
        .map(|i| Some(1.0 + 0.1 * (i as f64 * 1.7).sin()))
        .collect();
    let shifted = |d: f64, wobble: f64| -> Vec<Option<f64>> {
        base.iter()
            .enumerate()
            .map(|(i, r)| r.map(|r| r + d + wobble * (i as f64 * 2.3).cos()))
            .collect()
    };
    // As good within the windows' scatter: undecided; worse in every window: decided.
    assert!(paired_t(&shifted(0.005, 0.1), &base).abs() < LEAD_SIGNIFICANCE_T);
    assert!(paired_t(&shifted(0.2, 0.01), &base) > 10.0);
    // The same excess in every window is decided, identical residuals are not, and a residual
    // that is not finite decides nothing below a bound.
    assert!(paired_t(&shifted(0.2, 0.0), &base) > 1e6);
    assert_eq!(paired_t(&base, &base), 0.0);
    let mut broken = base.clone();
    broken[3] = Some(f64::NAN);
    assert!(paired_t(&broken, &base).is_nan());
    // The far fit is the best on the windows every fit has, unless it is in the near basin
    // (the near fit: `from` none) and not better than the near fit beyond the paired t.
    let minimum = |offset_s: f64| pose_fit::ScanMinimum {
        offset_s,
        cost_m2: 1.0,
        lever_m: Vector3::zeros(),
    };
    let lead_of = |fits: Vec<(PoseFit, Vec<Option<f64>>, bool)>| Lead {
        windows: vec![
            pose_fit::Window {
                range: 0..0,
                t_start: 0.0,
                t_end: 1.0
            };
            20
        ],
        fits: fits
            .into_iter()
            .map(|(fit, residuals, near)| LeadFit {
                from: (!near).then(|| minimum(fit.theta[0])),
                fit,
                residuals,
            })
            .collect(),
        beyond: Vec::new(),
    };
    let lead = lead_of(vec![
        (at(0.43), shifted(0.005, 0.1), false),
        (at(0.9), shifted(0.2, 0.01), false),
        (at(0.05), shifted(-0.001, 0.1), true),
    ]);
    assert_eq!(lead.far(Some(&at(0.5))).map(|f| f.theta[0]), Some(0.05));
    assert!(lead.far(Some(&at(0.05))).is_none());
    // In the near fit's basin: a fit the referee finds better in every window replaces it,
    // one as good within the windows' scatter does not.
    let in_basin = |residuals: Vec<Option<f64>>| {
        lead_of(vec![
            (at(0.1), shifted(0.02, 0.001), true),
            (at(0.15), residuals, false),
        ])
        .far(Some(&at(0.1)))
        .map(|f| f.theta[0])
    };
    assert_eq!(in_basin(base.clone()), Some(0.15));
    assert_eq!(in_basin(shifted(0.019, 0.1)), None);
    // The referee's windows: 80 s, fewer on a short mission, never shorter than the fit's.
    assert_eq!(referee_length_s(20.0, 900.0), REFEREE_WINDOW_S);
    assert_eq!(referee_length_s(20.0, 300.0), 50.0);
    assert_eq!(referee_length_s(20.0, 90.0), 20.0);
    // The valley reaches to the farthest candidate as good, not to one in the basin or one
    // worse in every window.
    let reach = |c: Vec<(f64, Vec<Option<f64>>)>| undecided_reach_s(0.1, &base, c);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(close(
        reach(vec![
            (0.15, shifted(0.0, 0.1)),
            (0.5, shifted(0.005, 0.1)),
            (0.9, shifted(0.2, 0.01)),
        ]),
        0.2
    ));
    assert_eq!(reach(vec![(0.9, shifted(0.2, 0.01))]), 0.0);
    assert!(close(reach(vec![(-0.7, shifted(-0.01, 0.1))]), 0.4));
    // A fit that climbed from its minimum (0.5 s) to a worse residual (0.9 s): the minimum
    // stands for it where it fits better and lies outside the basin; else the fit does.
    let climbed = |from_s: f64| Lead {
        windows: Vec::new(),
        fits: vec![LeadFit {
            fit: at(0.9),
            residuals: shifted(0.2, 0.01),
            from: Some(pose_fit::ScanMinimum {
                offset_s: from_s,
                cost_m2: 1.0,
                lever_m: Vector3::zeros(),
            }),
        }],
        beyond: Vec::new(),
    };
    let as_good = |_: &pose_fit::ScanMinimum| shifted(0.005, 0.1);
    let worse = |_: &pose_fit::ScanMinimum| shifted(0.3, 0.01);
    let lead = climbed(0.5);
    assert!(close(
        undecided_reach_s(0.1, &base, lead.candidates(0.1, as_good)),
        0.2
    ));
    assert_eq!(
        undecided_reach_s(0.1, &base, lead.candidates(0.1, worse)),
        0.0
    );
    let in_basin = climbed(0.15);
    let c: Vec<_> = in_basin.candidates(0.1, as_good).collect();
    assert_eq!(c[0].0, 0.9);
    // valley_s enters the constant's σ in quadrature and its parts.
    let p = profile(|_| 0.1);
    let mut m = ClockModel::constant(0.0, 0.0, String::new());
    let parts = set_parameters(
        &mut m,
        &fit(ClockShape::Constant, vec![0.1], vec![2e-3]),
        &p,
        0.215,
        Cuts::NONE,
    )
    .unwrap();
    assert!(m.sigma_s > 0.215 && m.sigma_s < 0.2151, "{m:?}");
    assert_eq!(parts.valley_s, 0.215);
    assert_eq!(parts.basins_s, 0.0);
}

#[test]
fn windows_in_two_basins_widen_the_constants_sigma_by_half_their_spread_and_say_so() {
    let p = profile(|_| 0.1);
    let mut m = ClockModel {
        alternation_s: 0.5,
        ..ClockModel::constant(0.0, 0.0, String::new())
    };
    let parts = set_parameters(
        &mut m,
        &fit(ClockShape::Constant, vec![0.1], vec![2e-3]),
        &p,
        0.0,
        Cuts::NONE,
    )
    .unwrap();
    assert!(m.sigma_s > 0.25 && m.sigma_s < 0.2501, "{m:?}");
    assert_eq!((parts.basins_s, parts.valley_s), (0.25, 0.0));
}

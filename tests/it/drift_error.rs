//! Drift Error on the shared simulated missions (truth in truth.json) and its invariants (proptest).
//!
//! The fixtures' estimate is shifted by the true clock offset (truth.json `time_offset.dt_true_s`); times
//! are seconds relative to the reference's first stamp. Unless a test says otherwise, path_eps = 1.0 m (the
//! default: the fixtures' reference has 2 cm of noise, which inflates shorter chords, see de_table).

use crate::common;

use nalgebra::{Rotation3, Vector3};
use proptest::prelude::*;
use trajdrift::metrics::drift_error::{drift_error, drift_error_windows, DriftParams};
use trajdrift::metrics::lever::LeverCorrection;

fn params(eps: f64, corr: LeverCorrection, lever_arm_m: f64) -> DriftParams {
    DriftParams {
        path_eps_m: eps,
        lever_correction: corr,
        lever_arm_m,
        ..DriftParams::default()
    }
}

const MEDIAN_MISSIONS: [&str; 4] = ["lever_arm", "gnss_outages", "legged", "straight"];

#[test]
fn median_de_at_5m_recovers_the_scale_error() {
    let Some(shared) = common::shared() else {
        return;
    };
    // path_eps = 1.0 m, lever arm a = 0.1 m (the defaults), both corrections.
    for m in MEDIAN_MISSIONS {
        let ms = common::load(&shared, m);
        let scale = ms.truth["estimate_model"]["scale_error"]
            .as_f64()
            .expect("scale_error");
        for corr in [LeverCorrection::Paper, LeverCorrection::None] {
            let r = drift_error(
                &ms.ref_t,
                &ms.ref_p,
                &ms.est_t_on_ref_clock,
                &ms.est_p,
                &params(1.0, corr, 0.1),
            )
            .expect("drift error");
            let s = r.stats.expect("windows");
            println!(
                "{m} {}: median {:.4} rmse {:.4} n {}",
                corr.as_str(),
                s.median,
                s.rmse,
                s.n
            );
            assert!(s.n >= 10, "{m}: only {} windows", s.n);
            assert!(
                (s.median - scale).abs() <= 0.005,
                "{m} ({}): median DE {:.4} vs scale error {scale}",
                corr.as_str(),
                s.median
            );
        }
    }
}

#[test]
fn legged_spins_are_excluded() {
    let Some(shared) = common::shared() else {
        return;
    };
    let ms = common::load(&shared, "legged_spins");
    let r = drift_error(
        &ms.ref_t,
        &ms.ref_p,
        &ms.est_t_on_ref_clock,
        &ms.est_p,
        &params(1.0, LeverCorrection::Paper, 0.1),
    )
    .expect("drift error");
    let spins = ms.truth["spins"]["intervals"].as_array().expect("spins");
    assert_eq!(spins.len(), 6);
    for s in spins {
        let a = s["t_start"].as_f64().expect("t_start") - ms.ref_origin_s;
        let b = s["t_end"].as_f64().expect("t_end") - ms.ref_origin_s;
        assert!(
            r.excluded_intervals
                .iter()
                .any(|iv| iv[0] <= a && b <= iv[1]),
            "spin [{a}, {b}] not inside any excluded interval {:?}",
            r.excluded_intervals
        );
    }
    // Nothing but the spins is excluded.
    assert_eq!(r.excluded_intervals.len(), 6, "{:?}", r.excluded_intervals);
    // With the spins out, no window carries a spin's arc: the worst window is far below the raw 0.47.
    let s = r.stats.expect("windows");
    println!("legged_spins: {s:?}");
    assert!(s.max < 0.3, "max DE {}", s.max);
}

#[test]
fn legged_spins_is_fast() {
    let Some(shared) = common::shared() else {
        return;
    };
    let ms = common::load(&shared, "legged_spins");
    let t = std::time::Instant::now();
    let r = drift_error_windows(
        &ms.ref_t,
        &ms.ref_p,
        &ms.est_t_on_ref_clock,
        &ms.est_p,
        &DriftParams::default(),
        &[1.0, 5.0, 10.0, 20.0],
    )
    .expect("drift error");
    let el = t.elapsed();
    println!("legged_spins, 4 window sizes: {el:?}");
    assert_eq!(r.len(), 4);
    // The test profile is opt-level 2; release is well under this.
    assert!(el.as_secs_f64() < 2.0, "took {el:?}");
}

#[test]
fn errors_on_bad_input() {
    let t = [0.0, 1.0];
    let p = [Vector3::zeros(); 2];
    let d = DriftParams::default();
    assert!(matches!(
        drift_error(&t, &p, &t, &p, &d),
        Err(trajdrift::Error::TooFewSamples { .. })
    ));
    let (t, p) = straight_line(50, 1.0);
    let later: Vec<f64> = t.iter().map(|x| x + 1000.0).collect();
    assert!(matches!(
        drift_error(&t, &p, &later, &p, &d),
        Err(trajdrift::Error::NoOverlap { .. })
    ));
}

fn straight_line(n: usize, v: f64) -> (Vec<f64>, Vec<Vector3<f64>>) {
    (0..n)
        .map(|i| (i as f64 * 0.1, Vector3::new(i as f64 * 0.1 * v, 0.0, 0.0)))
        .unzip()
}

/// A wavy planar reference path: speed `v`, heading wandering with `freqs`.
fn wavy(n: usize, v: f64, a1: f64, a2: f64) -> (Vec<f64>, Vec<Vector3<f64>>) {
    let mut p = Vector3::zeros();
    let mut out_t = Vec::with_capacity(n);
    let mut out_p = Vec::with_capacity(n);
    for i in 0..n {
        let t = i as f64 * 0.1;
        let h = a1 * (0.05 * t).sin() + a2 * (0.13 * t).cos();
        out_t.push(t);
        out_p.push(p);
        p += Vector3::new(h.cos(), h.sin(), 0.0) * v * 0.1;
    }
    (out_t, out_p)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn de_is_frame_invariant(yaw in -3.1f64..3.1, tx in -500.0f64..500.0, ty in -500.0f64..500.0,
                             tz in -10.0f64..10.0, a1 in 0.0f64..2.0, a2 in 0.0f64..2.0) {
        let (t, p) = wavy(1500, 1.0, a1, a2);
        let est: Vec<Vector3<f64>> = p.iter().enumerate()
            .map(|(i, x)| x * 1.01 + Vector3::new(0.0, 0.002 * ((i * 7919) % 13) as f64, 0.0))
            .collect();
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let moved: Vec<Vector3<f64>> = est.iter().map(|x| rot * x + Vector3::new(tx, ty, tz)).collect();
        for corr in [LeverCorrection::Paper, LeverCorrection::None, LeverCorrection::Fit] {
            let d = params(0.3, corr, 0.1);
            let a = drift_error(&t, &p, &t, &est, &d).unwrap();
            let b = drift_error(&t, &p, &t, &moved, &d).unwrap();
            prop_assert_eq!(a.windows.len(), b.windows.len());
            prop_assert!(!a.windows.is_empty());
            for (x, y) in a.windows.iter().zip(&b.windows) {
                prop_assert!((x.de - y.de).abs() < 1e-6, "{} vs {}", x.de, y.de);
            }
        }
    }

    #[test]
    fn scaled_estimate_gives_de_equal_to_scale(s in -0.1f64..0.1, a1 in 0.0f64..0.5, a2 in 0.0f64..0.5,
                                              eps in 0.0f64..0.5) {
        // Gentle curves (radius ≥ 10 m): α stays 1 even with the correction on, since |r_est − r_ref| > a.
        let (t, p) = wavy(1500, 1.0, a1, a2);
        let est: Vec<Vector3<f64>> = p.iter().map(|x| x * (1.0 + s)).collect();
        let r = drift_error(&t, &p, &t, &est, &params(eps, LeverCorrection::None, 0.1)).unwrap();
        prop_assert!(r.windows.len() >= 20);
        for w in &r.windows {
            prop_assert!((w.de - s.abs()).abs() < 2e-3, "de {} vs s {}", w.de, s);
        }
    }

    #[test]
    fn concentric_arcs_are_corrected(r in 2.0f64..10.0, d in -0.09f64..0.09, speed in 0.3f64..2.0) {
        // Reference on a circle of radius r, estimate sensor on the concentric circle of radius r + d,
        // both at the same angle (one rigid body turning about the centre). |d| stays 10 % inside the
        // gate a = 0.1 m: the radii are measured over ε-chords of sampled points, and at the gate's
        // edge (d = −0.0997 m, r = 2 m, 0.3 m/s) a measured |r_est − r_ref| just above a rightly leaves
        // α = 1 — that case is the gate working, not the correction failing.
        let n = 3000;
        let (mut t, mut rp, mut ep) = (vec![], vec![], vec![]);
        for i in 0..n {
            let ti = i as f64 * 0.1;
            let th = speed * ti / r;
            t.push(ti);
            rp.push(Vector3::new(r * th.cos(), r * th.sin(), 0.0));
            ep.push(Vector3::new((r + d) * th.cos(), (r + d) * th.sin(), 0.0) + Vector3::new(40.0, -3.0, 1.0));
        }
        let paper = drift_error(&t, &rp, &t, &ep, &params(0.3, LeverCorrection::Paper, 0.1)).unwrap();
        let none = drift_error(&t, &rp, &t, &ep, &params(0.3, LeverCorrection::None, 0.1)).unwrap();
        let sn = none.stats.unwrap();
        // The first window starts before either curvature signature is defined (eq. 1 needs an ε-chord
        // on both sides), so α = 1 on its first segments: it is left out.
        prop_assert!(paper.windows.len() > 3);
        // Eq. (1) measures κ over ε-chords, φ/(2r·sin(φ/2)) instead of 1/r: on the tightest circles
        // (r = 2 m, ε = 0.3 m) the two radii differ from the truth by slightly different amounts, which
        // leaves up to ~0.25 % after the correction (from ~4 % without).
        for w in &paper.windows[1..] {
            prop_assert!(w.de < 3e-3, "paper: DE {} at {} s (none: {})", w.de, w.t_start, sn.median);
        }
        prop_assert!((sn.median - (d / r).abs()).abs() < 2e-3, "none: {} vs {}", sn.median, d / r);
    }
}

/// The table asked for in the task: mission × correction × path_eps → DE at w = 5 m.
#[test]
#[ignore]
fn de_table() {
    let Some(shared) = common::shared() else {
        return;
    };
    println!(
        "| mission | correction | a (m) | path_eps (m) | median | RMSE | n | dropped | discarded ref | discarded est | excluded | truth raw median/RMS | truth body median/RMS |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for m in [
        "lever_arm",
        "gnss_outages",
        "legged",
        "legged_spins",
        "straight",
    ] {
        let ms = common::load(&shared, m);
        let tw = &ms.truth["drift_error"]["windows"]["5"];
        let truth = |k: &str| {
            format!(
                "{:.4} / {:.4} (n {})",
                tw[k]["median"].as_f64().unwrap_or(f64::NAN),
                tw[k]["rms"].as_f64().unwrap_or(f64::NAN),
                tw["n_windows"]
            )
        };
        let lever = ms.truth["lever_arms"]["horizontal_separation_m"]
            .as_f64()
            .unwrap_or(0.0);
        let mut arms = vec![0.1];
        if lever > 0.1 {
            arms.push(lever + 0.1);
        }
        for corr in [LeverCorrection::None, LeverCorrection::Paper] {
            for &a in if corr == LeverCorrection::None {
                &arms[..1]
            } else {
                &arms[..]
            } {
                for eps in [0.1, 0.3, 0.5, 1.0] {
                    let r = drift_error(
                        &ms.ref_t,
                        &ms.ref_p,
                        &ms.est_t_on_ref_clock,
                        &ms.est_p,
                        &params(eps, corr, a),
                    )
                    .expect("drift error");
                    let s = r.stats.expect("windows");
                    println!(
                        "| {m} | {} | {a:.1} | {eps} | {:.4} | {:.4} | {} | {} | {:.3} | {:.3} | {} | {} | {} |",
                        corr.as_str(),
                        s.median,
                        s.rmse,
                        s.n,
                        r.dropped_windows,
                        r.discarded_fraction,
                        r.discarded_fraction_estimate,
                        r.excluded_intervals.len(),
                        truth("raw"),
                        truth("body"),
                    );
                }
            }
        }
    }
}

//! Time offset estimation (step 2 of the paper): the masked FFT cross-correlation against its
//! definition, the curvature method on analytic trajectories, and both methods on the five simulated
//! missions of ../shared/fixtures against their truth.json.

use crate::common;

use std::time::Instant;

use nalgebra::{Rotation3, Vector3};
use proptest::prelude::*;
use trajdrift::align::curvature::CurvatureParams;
use trajdrift::align::time_offset::{
    estimate_time_offset, OffsetEstimate, OffsetMethod, OffsetParams, OffsetStatus,
};
use trajdrift::align::xcorr::{masked_ncc, masked_ncc_direct, overlap_sums, Centering};

fn run(m: &common::Mission, method: OffsetMethod, params: &OffsetParams) -> OffsetEstimate {
    estimate_time_offset(method, &m.ref_t, &m.ref_p, &m.est_t, &m.est_p, params)
        .unwrap_or_else(|e| panic!("{}: {e}", method.as_str()))
}

// ---- the masked FFT cross-correlation against its O(N·K) definition ----

fn signal_strategy(max_len: usize) -> impl Strategy<Value = (Vec<f64>, Vec<f64>)> {
    prop::collection::vec((-1.0f64..1.0, prop::bool::weighted(0.8)), 1..max_len).prop_map(|v| {
        v.into_iter()
            .map(|(x, m)| (x, if m { 1.0 } else { 0.0 }))
            .unzip()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn fft_ncc_matches_direct_sums(
        (a, ma) in signal_strategy(120),
        (b, mb) in signal_strategy(150),
        lo in -140i64..0,
        width in 0i64..300,
    ) {
        let hi = lo + width;
        for centering in [Centering::Raw, Centering::MeanRemoved] {
            let fft = masked_ncc(&a, &ma, &b, &mb, lo, hi, centering);
            let direct = masked_ncc_direct(&a, &ma, &b, &mb, lo, hi, centering);
            prop_assert_eq!(fft.len(), direct.len());
            prop_assert_eq!(&fft.overlap, &direct.overlap);
            for i in 0..fft.len() {
                let s = overlap_sums(&a, &ma, &b, &mb, fft.lag(i));
                // Skip the lags where a signal is (nearly) constant over the overlap: there the NCC
                // is 0/0 and both paths rightly give up, at slightly different thresholds.
                let (va, vb) = match centering {
                    Centering::Raw => (s.saa, s.sbb),
                    Centering::MeanRemoved => {
                        (s.saa - s.sa * s.sa / s.n.max(1.0), s.sbb - s.sb * s.sb / s.n.max(1.0))
                    }
                };
                if va < 1e-6 * s.saa.max(1e-12) || vb < 1e-6 * s.sbb.max(1e-12) || va < 1e-9 || vb < 1e-9 {
                    continue;
                }
                prop_assert!(
                    (fft.ncc[i] - direct.ncc[i]).abs() < 1e-7,
                    "lag {}: fft {} direct {} ({:?})", fft.lag(i), fft.ncc[i], direct.ncc[i], centering
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    /// Long signals against few lags: the correlation runs over many blocks of `a` (overlap-add), and
    /// must still give the direct sums at every lag.
    #[test]
    fn blocked_ncc_matches_direct_sums_over_many_blocks(
        (a, ma) in signal_strategy(6000),
        (b, mb) in signal_strategy(6000),
        lo in -80i64..40,
        width in 0i64..60,
    ) {
        let hi = lo + width;
        for centering in [Centering::Raw, Centering::MeanRemoved] {
            let fft = masked_ncc(&a, &ma, &b, &mb, lo, hi, centering);
            prop_assert_eq!(&fft.overlap, &masked_ncc_direct(&a, &ma, &b, &mb, lo, hi, centering).overlap);
            for i in 0..fft.len() {
                let s = overlap_sums(&a, &ma, &b, &mb, fft.lag(i));
                if s.n < 30.0 {
                    continue;
                }
                prop_assert!(
                    (fft.ncc[i] - s.ncc(centering)).abs() < 1e-9,
                    "lag {}: blocked {} direct {} ({:?})", fft.lag(i), fft.ncc[i], s.ncc(centering), centering
                );
            }
        }
    }
}

#[test]
fn ncc_of_a_shifted_copy_peaks_at_the_shift() {
    // b[j] = a[j − 7]: the lag pairing a[j] with b[j + 7] matches exactly.
    let a: Vec<f64> = (0..500)
        .map(|i| ((i as f64) * 0.37).sin().abs() + 0.1 * ((i as f64) * 1.3).cos())
        .collect();
    let mut b = vec![0.0; 7];
    b.extend_from_slice(&a);
    let ones = |n| vec![1.0; n];
    let r = masked_ncc(
        &a,
        &ones(a.len()),
        &b,
        &ones(b.len()),
        -50,
        50,
        Centering::Raw,
    );
    let best = (0..r.len())
        .max_by(|&x, &y| r.ncc[x].total_cmp(&r.ncc[y]))
        .unwrap();
    assert_eq!(r.lag(best), 7);
    assert!((r.ncc[best] - 1.0).abs() < 1e-9);
    assert_eq!(r.overlap[best], 500);
}

// ---- the curvature method on analytic trajectories ----

/// A planar path like a mission's: straight stretches and turns of irregular timing, size and sign
/// (yaw-rate bumps), at a speed that varies irregularly too, with a gentle climb. Integrated at 1 kHz
/// (midpoint rule); returns positions at t = i·1 ms, i in 0..n.
fn synthetic_path(duration_s: f64) -> Vec<Vector3<f64>> {
    let n = (duration_s * 1000.0) as usize + 1;
    // Deterministic but irregular: bump k at 4 + 7.3k + 2.5·sin(k²) seconds.
    let bump = |t: f64, k: usize, width: f64| {
        let c = 4.0 + 7.3 * k as f64 + 2.5 * ((k * k) as f64).sin();
        (-((t - c) / width).powi(2)).exp()
    };
    let bumps = (duration_s / 7.3) as usize + 2;
    let yaw_rate = |t: f64| {
        (0..bumps)
            .map(|k| {
                0.6 * ((k as f64) * 2.1).sin() * bump(t, k, 1.0 + 0.5 * ((k as f64) * 0.7).cos())
            })
            .sum::<f64>()
    };
    let speed = |t: f64| {
        1.0 + (0..bumps)
            .map(|k| 0.4 * ((k as f64) * 1.3 + 0.5).cos() * bump(t + 3.0, k, 2.0))
            .sum::<f64>()
    };
    let (mut p, mut psi) = (Vector3::new(3.0, -2.0, 0.5), 0.4);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        out.push(p);
        let tm = (i as f64 + 0.5) * 1e-3;
        let psi_mid = psi + 0.5e-3 * yaw_rate(tm - 0.25e-3);
        p += Vector3::new(psi_mid.cos(), psi_mid.sin(), 0.05 * (0.5 * tm).cos()) * speed(tm) * 1e-3;
        psi += 1e-3 * yaw_rate(tm);
    }
    out
}

/// Samples the 1 kHz path every `period_ms` from `phase_ms`, stamped on a clock that reads
/// t_true − `clock_offset_s` (so the true offset Δt is `clock_offset_s`).
fn sample(
    path: &[Vector3<f64>],
    period_ms: usize,
    phase_ms: usize,
    clock_offset_s: f64,
) -> (Vec<f64>, Vec<Vector3<f64>>) {
    (phase_ms..path.len())
        .step_by(period_ms)
        .map(|i| (i as f64 * 1e-3 - clock_offset_s, path[i]))
        .unzip()
}

#[test]
fn curvature_recovers_a_known_shift_to_a_millisecond() {
    let path = synthetic_path(200.0);
    let params = OffsetParams {
        curvature: CurvatureParams {
            eps_m: 0.3,
            ..Default::default()
        },
        ..Default::default()
    };
    for (dt, est_period, est_phase) in [
        (0.2373, 20, 3),
        (-1.8416, 20, 11),
        (7.5, 10, 0),
        (0.0416, 10, 7),
    ] {
        let (rt, rp) = sample(&path, 20, 0, 0.0);
        let (et, ep) = sample(&path, est_period, est_phase, dt);
        let r = estimate_time_offset(OffsetMethod::Curvature, &rt, &rp, &et, &ep, &params).unwrap();
        assert!(
            (r.offset_s - dt).abs() < 1e-3,
            "Δt {dt}: got {:.5} ({r:?})",
            r.offset_s
        );
        assert_eq!(r.status, OffsetStatus::Ok, "{r:?}");
        assert!(r.correlation > 0.99, "{r:?}");
    }
}

#[test]
fn speed_recovers_a_known_shift() {
    let path = synthetic_path(200.0);
    let (rt, rp) = sample(&path, 100, 0, 0.0);
    let (et, ep) = sample(&path, 10, 3, -0.6);
    let r = estimate_time_offset(
        OffsetMethod::Speed,
        &rt,
        &rp,
        &et,
        &ep,
        &OffsetParams::default(),
    )
    .unwrap();
    assert!((r.offset_s + 0.6).abs() < 2e-3, "{r:?}");
    assert_eq!(r.status, OffsetStatus::Ok, "{r:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(6))]
    #[test]
    fn curvature_offset_is_frame_invariant(
        yaw in -std::f64::consts::PI..std::f64::consts::PI,
        tx in -1000.0f64..1000.0,
        ty in -1000.0f64..1000.0,
        tz in -50.0f64..50.0,
    ) {
        let path = synthetic_path(90.0);
        let (rt, rp) = sample(&path, 50, 0, 0.0);
        let (et, ep) = sample(&path, 10, 4, 0.3141);
        let params = OffsetParams {
            curvature: CurvatureParams { eps_m: 0.3, ..Default::default() },
            ..Default::default()
        };
        let base = estimate_time_offset(OffsetMethod::Curvature, &rt, &rp, &et, &ep, &params).unwrap();
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let moved: Vec<Vector3<f64>> = ep.iter().map(|p| rot * p + Vector3::new(tx, ty, tz)).collect();
        let r = estimate_time_offset(OffsetMethod::Curvature, &rt, &rp, &et, &moved, &params).unwrap();
        prop_assert!((r.offset_s - base.offset_s).abs() < 1e-6, "{} vs {}", r.offset_s, base.offset_s);
        prop_assert!((r.correlation - base.correlation).abs() < 1e-6);
        prop_assert_eq!(r.status, base.status);
    }
}

#[test]
fn too_few_samples_and_no_overlap_are_errors() {
    let path = synthetic_path(60.0);
    let (rt, rp) = sample(&path, 50, 0, 0.0);
    let params = OffsetParams::default();
    let two = estimate_time_offset(
        OffsetMethod::Curvature,
        &rt,
        &rp,
        &rt[..2],
        &rp[..2],
        &params,
    );
    assert!(
        matches!(two, Err(trajdrift::Error::TooFewSamples { .. })),
        "{two:?}"
    );
    let far: Vec<f64> = rt.iter().map(|t| t + 1000.0).collect();
    for method in [OffsetMethod::Curvature, OffsetMethod::Speed] {
        let r = estimate_time_offset(method, &rt, &rp, &far, &rp, &params);
        assert!(
            matches!(r, Err(trajdrift::Error::NoOverlap { .. })),
            "{r:?}"
        );
    }
    let bad = OffsetParams {
        grid_s: 0.0,
        ..Default::default()
    };
    assert!(estimate_time_offset(OffsetMethod::Speed, &rt, &rp, &rt, &rp, &bad).is_err());
}

#[test]
fn serde_names_are_lowercase() {
    assert_eq!(
        serde_json::to_string(&OffsetMethod::Curvature).unwrap(),
        "\"curvature\""
    );
    assert_eq!(
        serde_json::to_string(&OffsetStatus::Weak).unwrap(),
        "\"weak\""
    );
    assert_eq!(OffsetMethod::Speed.as_str(), "speed");
    let m: OffsetMethod = serde_json::from_str("\"speed\"").unwrap();
    assert_eq!(m, OffsetMethod::Speed);
}

// ---- the five simulated missions ----

#[test]
fn speed_recovers_the_offset_on_every_mission() {
    let Some(shared) = common::shared() else {
        return;
    };
    let params = OffsetParams::default();
    for name in common::MISSIONS {
        let m = common::load(&shared, name);
        let r = run(&m, OffsetMethod::Speed, &params);
        let err = r.offset_s - m.dt_true;
        assert!(
            err.abs() < 0.020,
            "{name}: speed offset {:.4} s, truth {:.4} s ({r:?})",
            r.offset_s,
            m.dt_true
        );
        assert_eq!(r.status, OffsetStatus::Ok, "{name}: {r:?}");
    }
}

/// At the paper's ε (0.1 m legged, 0.3 m wheeled) the unsigned-κ peak on these missions is buried in
/// noise and lands far from the truth; the status must say so (see the table in `offset_table`).
#[test]
fn curvature_is_never_ok_when_far_off_on_the_missions() {
    let Some(shared) = common::shared() else {
        return;
    };
    for name in common::MISSIONS {
        let m = common::load(&shared, name);
        for eps in [0.1, 0.3] {
            let r = run(&m, OffsetMethod::Curvature, &table_params(eps, 2.0));
            let err = r.offset_s - m.dt_true;
            assert!(
                err.abs() < 0.1 || r.status == OffsetStatus::Weak,
                "{name}, ε {eps}: offset {:.3} s is {err:.3} s off but reported ok ({r:?})",
                r.offset_s
            );
        }
    }
}

fn table_params(eps_m: f64, dt_max_s: f64) -> OffsetParams {
    OffsetParams {
        curvature: CurvatureParams {
            eps_m,
            dt_max_s,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The table of both methods × five missions. Run with
/// `TRAJDRIFT_SHARED=/work/shared cargo test --release --test it -- --ignored --nocapture time_offset::offset_table`.
#[test]
#[ignore]
fn offset_table() {
    let Some(shared) = common::shared() else {
        return;
    };
    let configs: [(&str, f64, f64); 5] = [
        ("eps 0.1 m, dt_max 2 s", 0.1, 2.0),
        ("eps 0.3 m, dt_max 2 s", 0.3, 2.0),
        ("eps 1 m, dt_max 10 s", 1.0, 10.0),
        ("eps 2 m, dt_max 10 s", 2.0, 10.0),
        ("eps 0.5 m, dt_max 5 s", 0.5, 5.0),
    ];
    println!(
        "| method | ε, Δt_max | mission | Δt est (s) | truth (s) | error (ms) | NCC | confidence | status | time (ms) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let missions: Vec<(&str, common::Mission)> = common::MISSIONS
        .iter()
        .map(|&n| (n, common::load(&shared, n)))
        .collect();
    let mut rows = vec![(OffsetMethod::Speed, configs[0])];
    rows.extend(configs.iter().map(|&c| (OffsetMethod::Curvature, c)));
    for (method, (label, eps, dt_max)) in rows {
        let params = table_params(eps, dt_max);
        for (name, m) in &missions {
            let start = Instant::now();
            let r = estimate_time_offset(method, &m.ref_t, &m.ref_p, &m.est_t, &m.est_p, &params);
            let ms = start.elapsed().as_secs_f64() * 1e3;
            let label = if method == OffsetMethod::Speed {
                "window 2 s, Δt_max 2 s"
            } else {
                label
            };
            match r {
                Ok(r) => println!(
                    "| {} | {label} | {name} | {:+.4} | {:+.3} | {:+.1} | {:.3} | {:.2} | {:?} | {ms:.0} |",
                    method.as_str(),
                    r.offset_s,
                    m.dt_true,
                    (r.offset_s - m.dt_true) * 1e3,
                    r.correlation,
                    r.confidence,
                    r.status
                ),
                Err(e) => println!("| {} | {label} | {name} | error: {e} |", method.as_str()),
            }
        }
    }
}

/// The speed method's design choices (window, mean removal) measured on the five missions. Run with
/// `cargo test --release --test it -- --ignored --nocapture time_offset::speed_variants`.
#[test]
#[ignore]
fn speed_variants() {
    let Some(shared) = common::shared() else {
        return;
    };
    let missions: Vec<(&str, common::Mission)> = common::MISSIONS
        .iter()
        .map(|&n| (n, common::load(&shared, n)))
        .collect();
    println!("| window (s) | mean removed | mission errors (ms): lever_arm, gnss_outages, legged, legged_spins, straight | confidences |");
    println!("|---|---|---|---|");
    for window in [0.3, 0.5, 1.0, 2.0, 4.0] {
        for mean_removed in [true, false] {
            let params = OffsetParams {
                speed_window_s: window,
                speed_mean_removed: mean_removed,
                ..Default::default()
            };
            let mut errs = vec![];
            let mut confs = vec![];
            for (_, m) in &missions {
                match estimate_time_offset(
                    OffsetMethod::Speed,
                    &m.ref_t,
                    &m.ref_p,
                    &m.est_t,
                    &m.est_p,
                    &params,
                ) {
                    Ok(r) => {
                        errs.push(format!("{:+.1}", (r.offset_s - m.dt_true) * 1e3));
                        confs.push(format!(
                            "{:.2}{}",
                            r.confidence,
                            if r.status == OffsetStatus::Ok {
                                ""
                            } else {
                                "(weak)"
                            }
                        ));
                    }
                    Err(e) => errs.push(format!("error: {e}")),
                }
            }
            println!(
                "| {window} | {mean_removed} | {} | {} |",
                errs.join(", "),
                confs.join(", ")
            );
        }
    }
}

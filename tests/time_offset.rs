//! Time offset estimation (step 2 of the paper): the masked FFT cross-correlation against its
//! definition, the curvature method on analytic trajectories, and both methods on the five simulated
//! missions of ../shared/fixtures against their truth.json.

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::{Rotation3, Vector3};
use proptest::prelude::*;
use trajdrift::align::curvature::CurvatureParams;
use trajdrift::align::time_offset::{
    estimate_time_offset, OffsetEstimate, OffsetMethod, OffsetParams, OffsetStatus,
};
use trajdrift::align::xcorr::{masked_ncc, masked_ncc_direct, Centering};
use trajdrift::sources::tum::read_tum;

const MISSIONS: [&str; 5] = [
    "lever_arm",
    "gnss_outages",
    "legged",
    "legged_spins",
    "straight",
];

fn shared() -> PathBuf {
    std::env::var("TRAJDRIFT_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"))
}

/// A mission's reference and estimate as (times, positions), times in seconds from the reference's
/// first stamp, and its true offset.
struct Mission {
    ref_t: Vec<f64>,
    ref_p: Vec<Vector3<f64>>,
    est_t: Vec<f64>,
    est_p: Vec<Vector3<f64>>,
    dt_true: f64,
}

fn load(name: &str) -> Mission {
    let dir = shared().join("fixtures").join(name);
    assert!(
        dir.is_dir(),
        "{} is missing: set TRAJDRIFT_SHARED to the shared evidence folder",
        dir.display()
    );
    let reference = read_tum(&dir.join("reference.tum")).expect("reference.tum");
    let estimate = read_tum(&dir.join("estimate.tum")).expect("estimate.tum");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).expect("truth.json"))
            .expect("truth.json is JSON");
    let dt_true = truth["time_offset"]["dt_true_s"]
        .as_f64()
        .expect("time_offset.dt_true_s");
    let t0 = reference.stamps_ns[0];
    Mission {
        ref_t: reference.times_s(t0),
        ref_p: reference.positions.clone(),
        est_t: estimate.times_s(t0),
        est_p: estimate.positions.clone(),
        dt_true,
    }
}

fn run(m: &Mission, method: OffsetMethod, params: &OffsetParams) -> OffsetEstimate {
    estimate_time_offset(method, &m.ref_t, &m.ref_p, &m.est_t, &m.est_p, params)
        .unwrap_or_else(|e| panic!("{}: {e}", method.as_str()))
}

#[test]
fn speed_recovers_the_offset_on_every_mission() {
    let params = OffsetParams::default();
    for name in MISSIONS {
        let m = load(name);
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
/// `TRAJDRIFT_SHARED=/work/shared cargo test --release --test time_offset -- --ignored --nocapture offset_table`.
#[test]
#[ignore]
fn offset_table() {
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
    let missions: Vec<(&str, Mission)> = MISSIONS.iter().map(|&n| (n, load(n))).collect();
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
/// `cargo test --release --test time_offset -- --ignored --nocapture speed_variants`.
#[test]
#[ignore]
fn speed_variants() {
    let missions: Vec<(&str, Mission)> = MISSIONS.iter().map(|&n| (n, load(n))).collect();
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

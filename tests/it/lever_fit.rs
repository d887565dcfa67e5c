//! The fitted lateral lever-arm correction (`--lever-correction fit`) on the shared missions, through the
//! whole evaluation (mission.mcap, /reference/position vs /estimate/odom, path ε 1 m, speed offset), and
//! `--export-aligned`.

use crate::common;

use std::path::Path;

use trajdrift::align::time_offset::OffsetMethod;
use trajdrift::evaluate;
use trajdrift::metrics::lever::LeverCorrection;
use trajdrift::report::json::{DriftErrorReport, Report};
use trajdrift::sources::tum::read_tum;
use trajdrift::{EvalConfig, NamedInput};

use common::{mission, shared, truth, MISSIONS};

fn config(dir: &Path, correction: LeverCorrection, offset_s: Option<f64>) -> EvalConfig {
    let mut c = EvalConfig::new(
        Some(dir.join("mission.mcap")),
        NamedInput::topic("/reference/position"),
        vec![NamedInput::topic("/estimate/odom")],
    );
    c.params.offset_method = Some(OffsetMethod::Speed);
    c.params.path_eps = Some(1.0);
    c.params.lever_correction = Some(correction);
    c.params.time_offset = offset_s;
    c
}

fn run(c: &EvalConfig) -> Report {
    evaluate(c).unwrap_or_else(|e| panic!("{e}"))
}

fn de5(r: &Report) -> &DriftErrorReport {
    &r.estimates[0].drift_error[0]
}

#[test]
fn fit_recovers_the_scale_error_and_the_lateral_lever() {
    let Some(shared) = shared() else { return };
    for m in MISSIONS {
        let dir = mission(&shared, m);
        let t = truth(&shared, m);
        let scale = t["estimate_model"]["scale_error"].as_f64().expect("scale");
        let lateral = t["lever_arms"]["estimate_minus_reference"][1]
            .as_f64()
            .expect("lever");
        let r = run(&config(&dir, LeverCorrection::Fit, None));
        let d = de5(&r);
        let (median, rmse) = (d.median.expect("median"), d.rmse.expect("rmse"));
        let (s, lever) = (d.scale.expect("scale"), d.lateral_lever_m.expect("d"));
        println!("{m}: median {median:.4} rmse {rmse:.4} s {s:.4} d {lever:.3} (true {lateral})");
        assert_eq!(d.lever_correction, LeverCorrection::Fit);
        assert!(
            (median - scale).abs() <= 0.005,
            "{m}: median DE {median:.4} vs scale error {scale}"
        );
        if m == "legged_spins" {
            assert!(rmse < 0.04, "{m}: RMSE {rmse:.4}");
        }
        if matches!(m, "lever_arm" | "legged_spins" | "gnss_outages") {
            let tol = if lateral == 0.0 { 0.1 } else { 0.15 };
            assert!(
                (lever - lateral).abs() <= tol,
                "{m}: fitted lateral lever {lever:.3} m vs {lateral} m"
            );
        }
    }
}

#[test]
fn export_aligned_writes_the_shifted_estimate() {
    let Some(shared) = shared() else { return };
    let dir = mission(&shared, "legged_spins");
    let t = truth(&shared, "legged_spins");
    let dt = t["time_offset"]["dt_true_s"].as_f64().expect("dt");
    let out = std::env::temp_dir().join(format!("trajdrift-aligned-{}", std::process::id()));
    std::fs::create_dir_all(&out).expect("temp dir");
    let mut c = config(&dir, LeverCorrection::Fit, Some(dt));
    c.export_aligned = Some(out.join("aligned.tum"));
    run(&c);
    let aligned = read_tum(&out.join("aligned.tum")).expect("aligned.tum");
    let original = read_tum(&dir.join("estimate.tum")).expect("estimate.tum");
    assert_eq!(aligned.len(), original.len());
    let shift = aligned.stamps_ns[0] - original.stamps_ns[0];
    assert_eq!(shift, (dt * 1e9).round() as i64);
    assert!((aligned.positions[10] - original.positions[10]).norm() < 1e-6);
    // Several estimates: the name goes before the extension.
    c.estimates.push(NamedInput::topic("pose=/estimate/pose"));
    run(&c);
    assert!(out.join("aligned.estimate_odom.tum").is_file());
    assert!(out.join("aligned.pose.tum").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

/// The table in the reply: mission × correction → DE at w = 5 m (true offset applied).
#[test]
#[ignore]
fn correction_table() {
    let Some(shared) = shared() else { return };
    println!("| mission | correction | median | RMSE | n | s | d (m) | true lateral (m) |");
    println!("|---|---|---|---|---|---|---|---|");
    for m in MISSIONS {
        let dir = mission(&shared, m);
        let t = truth(&shared, m);
        let dt = t["time_offset"]["dt_true_s"].as_f64();
        let lateral = t["lever_arms"]["estimate_minus_reference"][1]
            .as_f64()
            .unwrap_or(f64::NAN);
        for corr in [
            LeverCorrection::None,
            LeverCorrection::Paper,
            LeverCorrection::Fit,
        ] {
            let r = run(&config(&dir, corr, dt));
            let d = de5(&r);
            let f = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{v:.4}"));
            println!(
                "| {m} | {} | {} | {} | {} | {} | {} | {lateral} |",
                corr.as_str(),
                f(d.median),
                f(d.rmse),
                d.windows,
                f(d.scale),
                f(d.lateral_lever_m)
            );
        }
    }
}

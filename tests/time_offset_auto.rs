//! Issue 3 (time offsets you can trust): `--offset-method auto` with automatic parameters on the shared
//! missions through `eval::evaluate` with all defaults, the clock drift, and one test per failure
//! mode of the curvature methods (noise vs ε, the Δx/v lead, unsigned κ's false confidence).

mod common;

use nalgebra::Vector3;
use trajdrift::align::auto_params::auto_params;
use trajdrift::align::curvature::CurvatureParams;
use trajdrift::align::time_offset::{estimate_time_offset, OffsetMethod, OffsetParams, OffsetStatus};
use trajdrift::sources::tum::read_tum;

use common::{mission, shared, truth, MISSIONS};

struct Tum {
    ref_t: Vec<f64>,
    ref_p: Vec<Vector3<f64>>,
    est_t: Vec<f64>,
    est_p: Vec<Vector3<f64>>,
}

fn load_tum(dir: &std::path::Path) -> Tum {
    let r = read_tum(&dir.join("reference.tum")).unwrap();
    let e = read_tum(&dir.join("estimate.tum")).unwrap();
    let t0 = r.stamps_ns[0];
    Tum {
        ref_t: r.times_s(t0),
        ref_p: r.positions.clone(),
        est_t: e.times_s(t0),
        est_p: e.positions.clone(),
    }
}

/// Every method × mission × (ε, Δt_max). Run with
/// `TRAJDRIFT_SHARED=/work/shared cargo test --release --test time_offset_auto -- --ignored --nocapture eps_table`.
#[test]
#[ignore]
fn eps_table() {
    let Some(shared) = shared() else { return };
    for m in MISSIONS {
        let d = load_tum(&mission(&shared, m));
        let dt = truth(&shared, m)["time_offset"]["dt_true_s"].as_f64().unwrap();
        let a = auto_params(&d.ref_t, &d.ref_p, 5.0, 2.0);
        println!("{m}: auto {a:?}");
        for (eps, dtm) in [(0.3, 2.0), (1.0, 5.0), (1.0, 10.0), (2.0, 5.0), (2.0, 10.0), (a.curvature_eps_m, a.curvature_dt_max_s)] {
            for method in [OffsetMethod::SignedCurvature, OffsetMethod::Curvature, OffsetMethod::Speed] {
                let p = OffsetParams {
                    curvature: CurvatureParams { eps_m: eps, dt_max_s: dtm, ..Default::default() },
                    ..Default::default()
                };
                match estimate_time_offset(method, &d.ref_t, &d.ref_p, &d.est_t, &d.est_p, &p) {
                    Ok(r) => println!(
                        "  {:>16} ε {eps:.2} Δt_max {dtm:.1}: err {:+8.1} ms ρ {:.3} conf {:.2} margin {:.3} def {:.2} {:?}",
                        method.as_str(), (r.offset_s - dt) * 1e3, r.correlation, r.confidence, r.margin, r.defined_fraction, r.status
                    ),
                    Err(e) => println!("  {} ε {eps} : {e}", method.as_str()),
                }
            }
        }
    }
}

//! Issue 10 (clock offsets over time): the README fixture's bias, the offset profile and its σ, the
//! model chosen from it (constant / linear / piecewise), on simulated missions with a known clock.

mod common;

use nalgebra::Vector3;
use trajdrift::align::auto_offset::auto_time_offset;
use trajdrift::align::clock_model::{clock_model, ClockModel};
use trajdrift::align::offset_profile::{OffsetProfile, ProfileParams};
use trajdrift::align::time_offset::{estimate_time_offset, OffsetMethod, OffsetParams};
use trajdrift::eval::config::{EvalConfig, NamedInput};
use trajdrift::eval::evaluate;
use trajdrift::report::json::Report;
use trajdrift::simulate::{default_route, simulate, ClockStep, Mission, MissionConfig};

/// Times in seconds from the mission start (reference clock for the reference, the estimate's own
/// clock for the estimate) and positions.
#[allow(clippy::type_complexity)]
fn series(m: &Mission) -> (Vec<f64>, Vec<Vector3<f64>>, Vec<f64>, Vec<Vector3<f64>>) {
    let t0 = m.config.start_time_ns;
    (
        m.reference.times_s(t0),
        m.reference.positions.clone(),
        m.estimate.times_s(t0),
        m.estimate.positions.clone(),
    )
}

/// The README fixture (`fixtures/sim_ground`, the simulator's defaults): its estimate sensor sits
/// 0.3 m to the left, so it moves at v − 0.3·ω in every turn; before the speed method took that out
/// (`lateral_lever_from_speed`) every method read +0.176…+0.185 s against the true +0.2 s.
#[test]
fn readme_fixture_offset_is_within_5_ms() {
    let m = simulate(&MissionConfig::default(), &default_route());
    let (rt, rp, et, ep) = series(&m);
    let a = auto_time_offset(&rt, &rp, &et, &ep, &OffsetParams::default()).unwrap();
    let err = a.estimate.offset_s - 0.2;
    println!(
        "sim_ground: Δt {:+.4} s, error {:+.1} ms",
        a.estimate.offset_s,
        err * 1e3
    );
    assert!(err.abs() <= 0.005, "error {:.1} ms", err * 1e3);
}

/// The speed method is immune to a lateral lever arm on either side (before: −75 ms per metre).
#[test]
fn speed_offset_ignores_a_lateral_lever() {
    for d in [-0.6, 0.3, 0.6] {
        let c = MissionConfig {
            est_lever_m: [0.0, d, 0.0],
            ..MissionConfig::default()
        };
        let m = simulate(&c, &default_route());
        let (rt, rp, et, ep) = series(&m);
        let o = estimate_time_offset(
            OffsetMethod::Speed,
            &rt,
            &rp,
            &et,
            &ep,
            &OffsetParams::default(),
        )
        .unwrap();
        let err = o.offset_s - 0.2;
        println!("lateral lever {d:+.1} m: speed error {:+.1} ms", err * 1e3);
        assert!(err.abs() <= 0.005, "lever {d}: error {:.1} ms", err * 1e3);
    }
}

/// The route repeated to last about `minutes`.
fn laps(minutes: f64) -> Vec<trajdrift::simulate::motion::Segment> {
    let one = default_route();
    let lap: f64 = one.iter().map(|s| s.duration_s).sum();
    let n = ((minutes * 60.0) / lap).round().max(1.0) as usize;
    std::iter::repeat_n(one, n).flatten().collect()
}

/// Whole-mission offset, profile and model of a simulated mission.
fn run(m: &Mission) -> (f64, OffsetProfile, ClockModel) {
    let (rt, rp, et, ep) = series(m);
    let params = OffsetParams::default();
    let a = auto_time_offset(&rt, &rp, &et, &ep, &params).unwrap();
    let (p, model) = clock_model(
        &rt,
        &rp,
        &et,
        &ep,
        &params,
        &a.estimate,
        &ProfileParams::default(),
        None,
    )
    .unwrap();
    (a.estimate.offset_s, p, model)
}

#[test]
#[ignore]
fn explore() {
    for (name, c, minutes) in [
        ("constant", MissionConfig::default(), 10.0),
        (
            "drift+100",
            MissionConfig {
                clock_drift_ppm: 100.0,
                ..MissionConfig::default()
            },
            20.0,
        ),
        (
            "step",
            MissionConfig {
                time_offset_s: 0.9,
                clock_step: Some(ClockStep {
                    at_s: 300.0,
                    offset_s: 0.3,
                }),
                ..MissionConfig::default()
            },
            10.0,
        ),
    ] {
        let t = std::time::Instant::now();
        let m = simulate(&c, &laps(minutes));
        let (whole, p, model) = run(&m);
        println!(
            "{name}: whole {whole:+.4} profile {} windows of {:.0}s scale {:.1} -> {:?} {}  ({:.1}s)",
            p.windows.len(),
            p.window_s,
            p.sigma_scale,
            model.model,
            model.reason,
            t.elapsed().as_secs_f64()
        );
        for s in &model.segments {
            println!(
                "   seg {:.1}..{:.1} {:+.4} ± {:.4}",
                s.t_start, s.t_end, s.offset_s, s.sigma_s
            );
        }
        for w in &p.windows {
            println!(
                "   t {:7.1} {:+.4} ± {:.4} ρ {:.2} {}",
                w.t, w.offset_s, w.sigma_s, w.correlation, w.usable
            );
        }
    }
}

/// `trajdrift eval RECORDING --reference REF --estimate EST`, all defaults but `edit`.
fn eval_mcap(path: &std::path::Path, reference: &str, estimate: &str) -> Report {
    let c = EvalConfig::new(
        Some(path.to_path_buf()),
        NamedInput::topic(reference),
        vec![NamedInput::topic(estimate)],
    );
    evaluate(&c, &|_| {}).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn print_report(name: &str, rep: &Report) {
    for e in &rep.estimates {
        let o = &e.time_offset;
        println!(
            "{name} {}: Δt {:+.4} ± {} s, model {:?}: {}",
            e.name,
            o.offset_s,
            o.sigma_s.map_or("-".into(), |s| format!("{s:.4}")),
            o.model,
            o.model_reason.clone().unwrap_or_default()
        );
        for w in &o.profile {
            println!(
                "   t {:9.1} {:+.4} ± {:.4} ρ {:.2}",
                w.t - rep.estimates[0].time_offset.profile[0].t,
                w.offset_s,
                w.sigma_s,
                w.correlation
            );
        }
    }
}

#[test]
#[ignore]
fn shared_table() {
    let Some(shared) = common::shared() else {
        return;
    };
    for m in common::MISSIONS
        .iter()
        .chain(&["clock_step", "clock_drift"])
    {
        let rep = eval_mcap(
            &common::mission(&shared, m).join("mission.mcap"),
            "/reference/position",
            "/estimate/odom",
        );
        println!("truth {}", common::truth(&shared, m)["time_offset"]);
        print_report(m, &rep);
    }
}

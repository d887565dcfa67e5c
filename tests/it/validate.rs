//! `trajdrift validate`: the calibration of the time alignment on the project's own varied missions.

use trajdrift::simulate::scenario::{MissionKind, Scenario, START_NS};
use trajdrift::validate::evaluate_pair;

/// Development aid: one mission's report in detail. `KIND=ground SEED=3 cargo test --release --test
/// validate -- --ignored --nocapture one_mission`.
#[test]
#[ignore]
fn one_mission() {
    let kind: MissionKind = std::env::var("KIND")
        .unwrap_or("ground".into())
        .parse()
        .unwrap();
    let seed: u64 = std::env::var("SEED").unwrap_or("1".into()).parse().unwrap();
    let mut s = Scenario::draw(kind, seed);
    // ZERO=yaw,scale,terrain,noise,ref_lever,est_lever,gait: switch effects off one by one.
    let zero = std::env::var("ZERO").unwrap_or_default();
    for z in zero.split(',') {
        match z {
            "yaw" => s.yaw_walk_deg_per_sqrt_s = 0.0,
            "scale" => s.scale_error = 0.0,
            "terrain" => s.terrain_m = 0.0,
            "noise" => {
                s.ref_noise_m = 0.0;
                s.ref_slow_noise_m = 0.0;
                s.est_noise_m = 0.0;
                s.est_attitude_noise_rad = 0.0;
            }
            "noise_x3" => {
                s.ref_noise_m *= 3.0;
                s.ref_slow_noise_m *= 3.0;
                s.est_noise_m *= 3.0;
                s.est_attitude_noise_rad *= 3.0;
            }
            "noise_half" => {
                s.ref_noise_m *= 0.5;
                s.ref_slow_noise_m *= 0.5;
                s.est_noise_m *= 0.5;
                s.est_attitude_noise_rad *= 0.5;
            }
            "ref_noise" => s.ref_noise_m = 0.0,
            "slow_noise" => s.ref_slow_noise_m = 0.0,
            "est_noise" => s.est_noise_m = 0.0,
            "att_noise" => s.est_attitude_noise_rad = 0.0,
            "ref_lever" => s.ref_lever_m = [0.0; 3],
            "est_lever" => s.est_lever_m = [0.0; 3],
            "gait" => s.gait = None,
            "latency" => s.receipt_latency_s = None,
            "lat_ref" => s.receipt_latency_s = s.receipt_latency_s.map(|l| (0.0, l.1)),
            "lat_est" => s.receipt_latency_s = s.receipt_latency_s.map(|l| (l.0, 0.0)),
            _ => {}
        }
    }
    println!(
        "{:?} seed {} ref {} Hz est {} Hz levers {:?} {:?} noise {:.3} yaw walk {:.3} latency {:?}",
        s.kind,
        s.seed,
        s.ref_rate_hz,
        s.est_rate_hz,
        s.est_lever_m,
        s.ref_lever_m,
        s.ref_noise_m,
        s.yaw_walk_deg_per_sqrt_s,
        s.receipt_latency_s
    );
    let m = s.simulate();
    let rep = evaluate_pair(m.reference, m.estimate).unwrap();
    let o = &rep.estimates[0].time_offset;
    let t0 = START_NS as f64 * 1e-9;
    println!(
        "method {} Δt {:+.5} σ {:?} truth(mid) {:+.5} model {:?}\n reason {:?}\n model {:?}\n lever {:?} ± {:?}",
        o.method,
        o.offset_s,
        o.sigma_s,
        s.offset_at(0.5 * m.duration_s),
        o.model,
        o.reason,
        o.model_reason,
        o.fitted_lever_m,
        o.fitted_lever_sigma_m
    );
    for m in &o.methods {
        println!(
            "  {} {:?} {}",
            m.method,
            m.offset_s.map(|v| v - s.offset_at(0.0)),
            m.status
        );
    }
    for w in &o.profile {
        let truth = s.offset_at(w.t - t0);
        println!(
            "  t {:7.1} err {:+7.2} ms σ {:6.2} ms q {:.4}",
            w.t - t0,
            (w.offset_s - truth) * 1e3,
            w.sigma_s * 1e3,
            w.correlation
        );
    }
    println!("warnings {:?}", rep.warnings);
}

/// Development aid: bias of the pose fit under one noise source at a time, on long missions.
#[test]
#[ignore]
fn noise_bias() {
    for (name, rn, en, an) in [
        ("ref 3 cm", 0.03, 0.0, 0.0),
        ("est 5 mm", 0.0, 0.005, 0.0),
        ("att 0.1°", 0.0, 0.0, 0.1f64.to_radians()),
    ] {
        for seed in 1..=4 {
            let mut s = Scenario::draw(MissionKind::Ground, seed);
            s.yaw_walk_deg_per_sqrt_s = 0.0;
            s.terrain_m = 0.0;
            s.scale_error = 0.0;
            s.ref_noise_m = rn;
            s.ref_slow_noise_m = 0.0;
            s.est_noise_m = en;
            s.est_attitude_noise_rad = an;
            s.outages.clear();
            s.ref_rate_hz = 10.0;
            s.est_rate_hz = 10.0;
            let m = s.simulate();
            let rep = evaluate_pair(m.reference, m.estimate).unwrap();
            let o = &rep.estimates[0].time_offset;
            println!(
                "{name} seed {seed}: {} err {:+.2} ms σ {:.2} ms",
                o.method,
                (o.offset_s - s.offset_at(0.0)) * 1e3,
                o.sigma_s.unwrap_or(f64::NAN) * 1e3
            );
        }
    }
}

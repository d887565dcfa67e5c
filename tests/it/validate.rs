//! `trajdrift validate`: the calibration of the time alignment on the project's own varied missions.
//!
//! The reduced run (3 missions of every kind, fixed seeds: 30 missions, a few seconds) holds the
//! issue's acceptance where a handful of missions can show it: no clock alarm on a constant clock,
//! legged missions within 10 ms, σ that neither hides the error nor dwarfs it, drifts within 10 ppm
//! or stated below the resolution, steps located. The full table (many seeds) is in
//! docs/evidence.md with its command.

use std::process::Command;

use trajdrift::align::clock_model::OffsetModel;
use trajdrift::report::json::TimeOffsetStatus;
use trajdrift::simulate::scenario::{MissionKind, Scenario, START_NS};
use trajdrift::{calibration, evaluate_pair, validate_missions, MissionGrade, ValidateOptions};

fn kind(g: &MissionGrade) -> MissionKind {
    g.kind.parse().expect("a known kind")
}

#[test]
fn reduced_validation_holds_the_calibration() {
    let grades = validate_missions(
        &ValidateOptions {
            per_kind: 3,
            ..ValidateOptions::default()
        },
        &|_, _| {},
    );
    assert_eq!(grades.len(), 3 * MissionKind::ALL.len());
    for g in &grades {
        assert_eq!(
            g.status,
            Some(TimeOffsetStatus::Ok),
            "{} {}: {:?}",
            g.kind,
            g.seed,
            g.error
        );
    }
    let constant: Vec<&MissionGrade> = grades.iter().filter(|g| kind(g).constant_clock()).collect();
    let c = calibration(&constant);
    let summary = format!("{c:?}");
    // No false clock alarm, no huge σ on a small error.
    assert_eq!(c.clock_alarms, 0, "{summary}");
    assert_eq!(c.sigma_too_large, 0, "{summary}");
    // A clean constant clock finishes without a warning (exit 0): the pose fit measured the lever
    // the signal searches suspected.
    for g in &constant {
        assert!(
            g.warnings.is_empty(),
            "{} {}: {:?}",
            g.kind,
            g.seed,
            g.warnings
        );
    }
    assert!(c.error_p50_s <= 0.003, "{summary}");
    assert!(c.error_max_s <= 0.015, "{summary}");
    // The headline σ: 21 missions, so looser than the acceptance's 85–98 % and [0.4, 1.2].
    assert!(c.coverage_2sigma >= 0.8, "{summary}");
    assert!(
        (0.25..=1.3).contains(&c.median_error_over_sigma),
        "{summary}"
    );
    // The windows' σ: hundreds of windows, the acceptance's bounds.
    assert!(c.windows >= 200, "{summary}");
    assert!(
        (0.85..=0.98).contains(&c.window_coverage_2sigma),
        "{summary}"
    );
    assert!(
        (0.4..=1.2).contains(&c.window_median_error_over_sigma),
        "{summary}"
    );
    // Legged missions with levers within 10 ms.
    for g in constant.iter().filter(|g| g.legged) {
        let e = g.error_s.expect("applied");
        assert!(
            e.abs() <= 0.010,
            "{} {}: {:+.1} ms",
            g.kind,
            g.seed,
            e * 1e3
        );
    }
    for g in &grades {
        let what = format!("{} {}: {:?}", g.kind, g.seed, g.model);
        match kind(g) {
            // Long drifting missions: linear within 10 ppm.
            MissionKind::Drift => {
                assert_eq!(g.model, Some(OffsetModel::Linear), "{what}");
                let d = g.drift_ppm.expect("a drift");
                assert!((d - g.drift_true_ppm).abs() <= 10.0, "{what} {d}");
            }
            // 5 minutes at 50 ppm: linear within 10 ppm, or constant with the resolution stated
            // and σ covering the headline's error.
            MissionKind::ShortDrift => match g.model {
                Some(OffsetModel::Linear) => {
                    let d = g.drift_ppm.expect("a drift");
                    assert!((d - g.drift_true_ppm).abs() <= 10.0, "{what} {d}");
                }
                _ => {
                    assert!(g.drift_ppm.is_none(), "{what}");
                    let r = g.drift_resolution_ppm.expect("the resolution stated");
                    assert!(r > 0.0, "{what}");
                    let (e, s) = (g.error_s.unwrap(), g.sigma_s.unwrap());
                    assert!(e.abs() <= 2.0 * s, "{what}: {e} ± {s}");
                }
            },
            // Steps: located within 15 s, each segment within 20 ms.
            MissionKind::Step => {
                assert_eq!(g.model, Some(OffsetModel::Piecewise), "{what}");
                assert!(g.step_time_error_s.unwrap().abs() <= 15.0, "{what}");
                assert!(g.step_segment_error_s.unwrap() <= 0.020, "{what}");
            }
            _ => {}
        }
    }
}

/// Two step missions (legged, 5 Hz reference) where profile windows started on the wrong side of
/// the step or without a lever settle at sharp roots of their own unless searched for a deeper one:
/// the step is found and each segment is within 20 ms. (3035's step is still located 17 s off and
/// two of its windows stay in the other basin, below the search's χ² threshold.)
#[test]
fn a_step_is_found_where_windows_settle_in_another_basin() {
    for seed in [1003, 3035] {
        let grades = validate_missions(
            &ValidateOptions {
                kinds: vec![MissionKind::Step],
                per_kind: 1,
                first_seed: seed,
            },
            &|_, _| {},
        );
        let g = &grades[0];
        let what = format!("step {seed}: {:?} {:?}", g.model, g.step_segment_error_s);
        assert_eq!(g.model, Some(OffsetModel::Piecewise), "{what}");
        assert!(g.step_segment_error_s.unwrap() <= 0.020, "{what}");
    }
}

/// A near-straight mission where no search is confident (its speed varies too little for a clear
/// peak, its turns too few for curvature): the pose fit from the searches' answers tells the
/// forward lever from Δt, and its answer is applied with a σ that covers its error.
#[test]
fn a_weak_search_is_rescued_by_the_pose_fit_where_it_tells_the_lever_from_the_offset() {
    let grades = validate_missions(
        &ValidateOptions {
            kinds: vec![MissionKind::NearStraight],
            per_kind: 1,
            first_seed: 34,
        },
        &|_, _| {},
    );
    let g = &grades[0];
    let what = format!(
        "near_straight 34: {:?} {:?} {:?}",
        g.status, g.error_s, g.sigma_s
    );
    assert_eq!(g.status, Some(TimeOffsetStatus::Ok), "{what}");
    let (e, sigma) = (g.error_s.unwrap(), g.sigma_s.unwrap());
    assert!(
        e.abs() <= 0.010 && e.abs() <= 2.0 * sigma && sigma <= 0.050,
        "{what}"
    );
}

#[test]
fn validate_command_prints_the_table_and_writes_grades() {
    let dir = std::env::temp_dir().join(format!("trajdrift-validate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("grades.json");
    let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args([
            "validate",
            "--missions",
            "1",
            "--kind",
            "legged,step",
            "--json",
        ])
        .arg(&json)
        .output()
        .expect("run trajdrift");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("| legged | 1 | 1 |"), "{table}");
    assert!(table.contains("| step: seed |"), "{table}");
    let grades: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(grades.as_array().map(Vec::len), Some(2), "{grades}");
    assert_eq!(grades[0]["status"], "ok", "{grades}");
    // Usage errors exit 2.
    let bad = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(["validate", "--missions", "0"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

/// Development aid: one mission's report in detail. `KIND=ground SEED=3 cargo test --release --test
/// it -- --ignored --nocapture one_mission` (`REDRAW=12`: the scatter over fresh noise draws).
#[test]
#[ignore]
fn one_mission() {
    let kind: MissionKind = std::env::var("KIND")
        .unwrap_or("ground".into())
        .parse()
        .unwrap();
    let seed: u64 = std::env::var("SEED").unwrap_or("1".into()).parse().unwrap();
    let mut s = Scenario::draw(kind, seed);
    // ZERO=yaw,scale,terrain,noise,ref_lever,est_lever,gait,latency,lat_ref,lat_est,… (the match
    // below): switch effects off one by one; REF_HZ, EST_HZ: other rates.
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
    if let Ok(v) = std::env::var("EST_HZ") {
        s.est_rate_hz = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("REF_HZ") {
        s.ref_rate_hz = v.parse().unwrap();
    }
    // REDRAW=K: the same route, rates, levers and gait K times, the noise, terrain, first heading,
    // both sensors' sampling phases and receipt latencies drawn again (the scenario's seed moved):
    // how far Δt scatters, against its σ.
    if let Ok(k) = std::env::var("REDRAW") {
        let k: u64 = k.parse().unwrap();
        let t0 = START_NS as f64 * 1e-9;
        let mut errors = Vec::new();
        for r in 0..k {
            let mut d = s.clone();
            if r > 0 {
                d.seed = seed * 1000 + r;
            }
            let m = d.simulate();
            let rep = evaluate_pair(m.reference, m.estimate).unwrap();
            let o = &rep.estimates[0].time_offset;
            let mid = match (o.profile.first(), o.profile.last()) {
                (Some(a), Some(b)) => 0.5 * (a.t + b.t) - t0,
                _ => 0.5 * m.duration_s,
            };
            let e = o.offset_s - d.offset_at(mid);
            let lever = o.fitted_lever_m.unwrap_or([f64::NAN; 3]);
            println!(
                "draw {r}: error {:+.1} ms, σ {:.1} ms, lever error ({:+.3}, {:+.3}, {:+.3}) m",
                e * 1e3,
                o.sigma_s.unwrap_or(f64::NAN) * 1e3,
                lever[0] - (d.est_lever_m[0] - d.ref_lever_m[0]),
                lever[1] - (d.est_lever_m[1] - d.ref_lever_m[1]),
                lever[2] - (d.est_lever_m[2] - d.ref_lever_m[2]),
            );
            errors.push(e);
        }
        let n = errors.len() as f64;
        let mean = errors.iter().sum::<f64>() / n;
        let sd =
            (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        println!(
            "mean {:+.1} ms, sd {:.1} ms over {k} draws",
            mean * 1e3,
            sd * 1e3
        );
        return;
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

/// `trajdrift validate ARGS`, which must succeed: its table.
fn validate_table(args: &[&std::ffi::OsStr]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .arg("validate")
        .args(args)
        .output()
        .expect("run trajdrift");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn validate_like_reads_the_recording_s_shape_and_grades_missions_of_it() {
    let dir = std::env::temp_dir().join(format!("trajdrift-like-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("like.json");
    let fixture = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/sim_ground/mission.mcap"
    );
    let table = validate_table(&[
        "--like".as_ref(),
        fixture.as_ref(),
        "--reference".as_ref(),
        "/reference/position".as_ref(),
        "--estimate".as_ref(),
        "/estimate/odom".as_ref(),
        "--missions".as_ref(),
        "4".as_ref(),
        "--json".as_ref(),
        json.as_os_str(),
    ]);
    assert!(table.contains("reference 10.0 Hz"), "{table}");
    assert!(table.contains("estimate 20.0 Hz"), "{table}");
    assert!(table.contains("| 4 | 4 |"), "{table}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(v["missions"].as_array().map(Vec::len), Some(4), "{v}");
    assert_eq!(v["shape"]["legged"], false, "{v}");
    for g in v["missions"].as_array().unwrap() {
        assert_eq!(g["kind"], "like");
        assert!(g["error_s"].as_f64().unwrap().abs() < 0.01, "{g}");
    }
    // --like needs both topics; an output over the input is refused.
    let missing = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args([
            "validate",
            "--like",
            fixture,
            "--reference",
            "/reference/position",
        ])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    let over = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(["validate", "--like", fixture])
        .args([
            "--reference",
            "/reference/position",
            "--estimate",
            "/estimate/odom",
        ])
        .args(["--json", fixture])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&over.stderr);
    assert_eq!(over.status.code(), Some(2), "{err}");
    assert!(err.contains("would destroy the input"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn validate_like_takes_its_shape_from_text_trajectories_too() {
    let Some(shared) = crate::common::shared() else {
        return;
    };
    let dir = shared.join("fixtures").join("legged");
    let (reference, estimate) = (dir.join("reference.tum"), dir.join("estimate.tum"));
    let table = validate_table(&[
        "--missions".as_ref(),
        "2".as_ref(),
        "--reference-file".as_ref(),
        reference.as_os_str(),
        "--estimate-file".as_ref(),
        estimate.as_os_str(),
    ]);
    assert!(table.contains("reference 20.0 Hz"), "{table}");
    assert!(table.contains("simulated as a legged robot"), "{table}");
    assert!(table.contains("| 2 | 2 |"), "{table}");
}

/// A legged robot that stands 15 s, then walks at one speed without turning in place, its estimate's sensor
/// 0.3 m ahead of the reference's point: the signal searches read that lever as a clock offset of
/// 1 s (0.3 m at 0.3 m/s), beyond the pose fit's usual reach from their answer. The lead search
/// (`align::pose_model`) finds the offset along the valley where Δt trades against the lever.
#[test]
fn a_walk_with_the_sensor_ahead_is_not_read_as_a_clock_offset() {
    use trajdrift::simulate::scenario::Leg;
    let mut s = Scenario::draw(MissionKind::Legged, 7);
    let leg = |k: usize| Leg {
        duration_s: 15.0,
        speed_mps: if k == 0 { 0.0 } else { 0.3 },
        curvature: if k == 0 {
            0.0
        } else {
            0.4 * (k as f64 * 1.7).sin()
        },
        spin_rps: 0.0,
    };
    s.route = (0..41).map(leg).collect();
    s.outages.clear();
    s.jumps.clear();
    s.receipt_latency_s = None;
    s.clock_step = None;
    s.clock_drift_ppm = 0.0;
    s.ref_lever_m = [0.0, 0.0, 0.0];
    s.est_lever_m = [0.3, 0.05, 0.2];
    s.time_offset_s = 0.1;
    let g = trajdrift::run_scenario(&s);
    let what = format!(
        "{:?} {:?} {:?} {:?}",
        g.method, g.model, g.error_s, g.sigma_s
    );
    assert_eq!(g.status, Some(TimeOffsetStatus::Ok), "{what}");
    assert!(g.error_s.unwrap().abs() <= 0.010, "{what}");
    assert!(
        g.error_s.unwrap().abs() <= 3.0 * g.sigma_s.unwrap(),
        "{what}"
    );
}

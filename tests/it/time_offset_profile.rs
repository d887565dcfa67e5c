//! Clock offsets over time: the README fixture's bias, the offset profile and its σ, the
//! model chosen from it (constant / linear / piecewise), on simulated missions with a known clock.

use crate::common;
use trajdrift::diag::WarningCode;

use nalgebra::Vector3;
use trajdrift::align::auto_offset::auto_time_offset;
use trajdrift::align::clock_model::{clock_model, ClockModel, OffsetModel};
use trajdrift::align::offset_profile::{OffsetProfile, ProfileParams};
use trajdrift::align::time_offset::{estimate_time_offset, OffsetMethod, OffsetParams};
use trajdrift::evaluate;
use trajdrift::report::json::Report;
use trajdrift::simulate::motion::Segment;
use trajdrift::simulate::{default_route, simulate, ClockStep, Mission, MissionConfig};
use trajdrift::{evaluate_trajectories, read, EvalConfig, NamedInput, Parameters, ReadOptions};

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
    evaluate(&c).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
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

/// A legged robot's lap: slow walking, tight turns, stops; about 150 s.
fn legged_lap() -> Vec<Segment> {
    let s = |d: f64, v: f64, k: f64| Segment {
        duration_s: d,
        speed_mps: v,
        curvature: k,
    };
    vec![
        s(3.0, 0.0, 0.0),
        s(15.0, 0.5, 0.0),
        s(12.0, 0.4, 0.8),
        s(10.0, 0.6, 0.0),
        s(14.0, 0.35, -1.0),
        s(4.0, 0.0, 0.0),
        s(12.0, 0.5, 0.4),
        s(16.0, 0.45, -0.5),
        s(10.0, 0.6, 0.0),
        s(18.0, 0.3, 1.2),
        s(12.0, 0.5, -0.2),
        s(20.0, 0.4, 0.6),
        s(4.0, 0.0, 0.0),
    ]
}

/// `lap` repeated to last about `minutes`.
fn repeat(lap: Vec<Segment>, minutes: f64) -> Vec<Segment> {
    let one: f64 = lap.iter().map(|s| s.duration_s).sum();
    let n = ((minutes * 60.0) / one).round().max(1.0) as usize;
    std::iter::repeat_n(lap, n).flatten().collect()
}

/// Acceptance: a 20-minute wheeled mission with a +100 ppm clock is `linear`, within 10 ppm.
#[test]
fn a_100_ppm_clock_is_linear_within_10_ppm() {
    let c = MissionConfig {
        clock_drift_ppm: 100.0,
        ..MissionConfig::default()
    };
    let (_, _, model) = run(&simulate(&c, &laps(20.0)));
    let ppm = model.drift_ppm.unwrap();
    println!(
        "+100 ppm, 20 min: {:?}, {ppm:+.1} ppm ({})",
        model.model, model.reason
    );
    assert_eq!(model.model, OffsetModel::Linear, "{}", model.reason);
    assert!((ppm - 100.0).abs() <= 10.0, "{ppm} ppm");
}

/// Acceptance: a 15-minute legged mission (0.2 m forward lever, slow, tight turns) at −150 ppm is
/// measured within 15 ppm.
#[test]
fn a_legged_minus_150_ppm_clock_is_within_15_ppm() {
    let c = MissionConfig {
        clock_drift_ppm: -150.0,
        est_lever_m: [0.2, 0.0, 0.0],
        time_offset_s: 0.07,
        seed: 11,
        ..MissionConfig::default()
    };
    let (_, _, model) = run(&simulate(&c, &repeat(legged_lap(), 15.0)));
    let ppm = model.drift_ppm.unwrap();
    println!(
        "legged −150 ppm, 15 min: {:?}, {ppm:+.1} ppm ({})",
        model.model, model.reason
    );
    assert_eq!(model.model, OffsetModel::Linear, "{}", model.reason);
    assert!((ppm + 150.0).abs() <= 15.0, "{ppm} ppm");
}

/// Acceptance: a 10-minute mission whose offset steps from 0.9 s to 0.3 s at 300 s is `piecewise`,
/// the change within 15 s of 300 s, each segment within 20 ms.
#[test]
fn a_clock_step_is_piecewise() {
    let c = MissionConfig {
        time_offset_s: 0.9,
        clock_step: Some(ClockStep {
            at_s: 300.0,
            offset_s: 0.3,
        }),
        ..MissionConfig::default()
    };
    let (_, _, model) = run(&simulate(&c, &laps(10.0)));
    println!(
        "step 0.9 → 0.3 s at 300 s: {:?} {:?}",
        model.model, model.segments
    );
    assert_eq!(model.model, OffsetModel::Piecewise, "{}", model.reason);
    assert_eq!(model.segments.len(), 2, "{:?}", model.segments);
    let (a, b) = (model.segments[0], model.segments[1]);
    assert!((b.t_start - 300.0).abs() <= 15.0, "change at {}", b.t_start);
    assert!((a.offset_s - 0.9).abs() <= 0.02, "{a:?}");
    assert!((b.offset_s - 0.3).abs() <= 0.02, "{b:?}");
}

/// A position jump of the estimate (a localiser correcting itself by 2 m, twice) is not a clock step.
#[test]
fn position_jumps_are_not_clock_steps() {
    let mut m = simulate(&MissionConfig::default(), &laps(10.0));
    let t0 = m.config.start_time_ns;
    for (i, s) in m.estimate.stamps_ns.clone().iter().enumerate() {
        let t = (s - t0) as f64 * 1e-9;
        if t > 200.0 {
            m.estimate.positions[i].x += 2.0;
        }
        if t > 400.0 {
            m.estimate.positions[i].y -= 2.0;
        }
    }
    let (_, _, model) = run(&m);
    println!("position jumps: {:?} ({})", model.model, model.reason);
    assert_eq!(model.model, OffsetModel::Constant, "{}", model.reason);
}

/// The simulated constant-offset missions of the coverage table: seeds, offsets, lever arms, noise,
/// routes and lengths varied.
fn coverage_missions() -> Vec<(String, MissionConfig, Vec<Segment>)> {
    let offsets = [0.2, -0.35, 0.07, 1.3, -2.1];
    let levers = [
        [0.0, 0.3, 0.0],
        [0.0, 0.0, 0.0],
        [0.3, 0.0, 0.0],
        [0.0, -0.3, 0.0],
    ];
    (0..24u64)
        .map(|k| {
            let legged = k % 4 == 3;
            let c = MissionConfig {
                seed: 100 + k,
                time_offset_s: offsets[k as usize % offsets.len()],
                est_lever_m: levers[k as usize % levers.len()],
                ref_noise_m: [0.02, 0.01, 0.03][k as usize % 3],
                scale_error: [0.02, -0.01, 0.0][k as usize % 3],
                ..MissionConfig::default()
            };
            let minutes = [4.0, 6.0, 8.0][k as usize % 3];
            let (name, route) = if legged {
                ("legged", repeat(legged_lap(), minutes))
            } else {
                ("wheeled", laps(minutes))
            };
            (format!("{name} {minutes:.0} min seed {}", c.seed), c, route)
        })
        .collect()
}

/// Acceptance (honest σ): over 24 simulated constant-offset missions, |Δt − truth| ≤ 2σ in ≥ 85 % of
/// them with a median σ ≤ 10 ms, and the same coverage for the profile's usable windows. Prints the
/// table: `cargo test --release --test it -- --nocapture time_offset_profile::coverage_table`.
#[test]
fn coverage_table() {
    let mut covered = 0;
    let mut sigmas = Vec::new();
    let (mut w_in, mut w_all) = (0usize, 0usize);
    let missions = coverage_missions();
    println!(
        "| mission | Δt true | Δt | error ms | σ ms | within 2σ | model | windows within 2σ |"
    );
    for (name, c, route) in &missions {
        let m = simulate(c, route);
        let (whole, p, model) = run(&m);
        let truth = c.time_offset_s;
        let err = whole - truth;
        let ok = err.abs() <= 2.0 * model.sigma_s;
        covered += usize::from(ok);
        sigmas.push(model.sigma_s);
        let u = p.usable();
        let inside = u
            .iter()
            .filter(|w| (w.offset_s - truth).abs() <= 2.0 * w.sigma_s)
            .count();
        w_in += inside;
        w_all += u.len();
        println!(
            "| {name} | {truth:+.3} | {whole:+.4} | {:+.1} | {:.1} | {ok} | {} | {inside}/{} |",
            err * 1e3,
            model.sigma_s * 1e3,
            model.model.as_str(),
            u.len()
        );
        assert_eq!(
            model.model,
            OffsetModel::Constant,
            "{name}: {}",
            model.reason
        );
    }
    sigmas.sort_by(f64::total_cmp);
    let median = sigmas[sigmas.len() / 2];
    let share = covered as f64 / missions.len() as f64;
    let w_share = w_in as f64 / w_all as f64;
    println!(
        "Δt within 2σ: {covered}/{} = {:.0} %, median σ {:.1} ms; profile windows within 2σ: {w_in}/{w_all} = {:.0} %",
        missions.len(),
        share * 100.0,
        median * 1e3,
        w_share * 100.0
    );
    assert!(share >= 0.85, "coverage {share}");
    assert!(median <= 0.010, "median σ {median}");
    assert!(w_share >= 0.85, "window coverage {w_share}");
}

/// Acceptance: the five shared constant-offset missions are `constant` with no drift or step
/// warning; `clock_step` is `piecewise` (change within 15 s of its truth, segments within 20 ms) and
/// `clock_drift` `linear` (its 80 ppm within 15 ppm), each with its warning.
#[test]
fn shared_missions_get_their_clock_model() {
    let Some(shared) = common::shared() else {
        return;
    };
    let eval = |m: &str| {
        eval_mcap(
            &common::mission(&shared, m).join("mission.mcap"),
            "/reference/position",
            "/estimate/odom",
        )
    };
    for m in common::MISSIONS {
        let rep = eval(m);
        let o = &rep.estimates[0].time_offset;
        println!("{m}: {:?} {:?}", o.model, o.model_reason);
        assert_eq!(
            o.model,
            Some(OffsetModel::Constant),
            "{m}: {:?}",
            o.model_reason
        );
        assert!(!has_clock_warning(&rep), "{m}: {:?}", rep.warnings);
    }
    let rep = eval("clock_step");
    let truth = common::truth(&shared, "clock_step");
    let o = &rep.estimates[0].time_offset;
    println!("clock_step: {:?} {:?}", o.model_reason, o.segments);
    assert_eq!(
        o.model,
        Some(OffsetModel::Piecewise),
        "{:?}",
        o.model_reason
    );
    assert!(rep
        .warnings
        .iter()
        .any(|w| w.code == WarningCode::ClockStepSuspected));
    let t0 = o.profile[0].t - 0.5 * o.profile_window_s.unwrap();
    let at = truth["time_offset"]["clock_step_t_s"].as_f64().unwrap();
    assert_eq!(o.segments.len(), 2, "{:?}", o.segments);
    assert!(
        (o.segments[1].t_start - t0 - at).abs() <= 15.0,
        "{:?}",
        o.segments
    );
    let before = truth["time_offset"]["dt_true_s"].as_f64().unwrap();
    let after = truth["time_offset"]["dt_after_step_s"].as_f64().unwrap();
    assert!(
        (o.segments[0].offset_s - before).abs() <= 0.02,
        "{:?}",
        o.segments
    );
    assert!(
        (o.segments[1].offset_s - after).abs() <= 0.02,
        "{:?}",
        o.segments
    );

    let rep = eval("clock_drift");
    let o = &rep.estimates[0].time_offset;
    println!("clock_drift: {:?}", o.model_reason);
    assert_eq!(o.model, Some(OffsetModel::Linear), "{:?}", o.model_reason);
    assert!(
        (o.drift_ppm.unwrap() - 80.0).abs() <= 15.0,
        "{:?}",
        o.drift_ppm
    );
    assert!(rep
        .warnings
        .iter()
        .any(|w| w.code == WarningCode::ClockDriftSuspected));
}

fn has_clock_warning(rep: &Report) -> bool {
    rep.warnings.iter().any(|w| {
        w.code == WarningCode::ClockDriftSuspected || w.code == WarningCode::ClockStepSuspected
    })
}

/// Acceptance: the real recordings of `shared/evo-data` (EuRoC V102, TUM fr1_xyz and fr2_desk, KITTI
/// 00 ORB and S-PTAM with times, the ROS 1 example bag's two estimates, nav2 `/amcl_pose` and
/// `/tf:map:base_footprint` against `/odom`) keep one constant offset, with no drift or step warning.
#[test]
fn real_recordings_are_constant() {
    let Some(shared) = common::shared() else {
        return;
    };
    let evo = shared.join("evo-data");
    let files = |r: &str, e: &str| {
        let mut c = EvalConfig::new(
            None,
            NamedInput::file(&evo.join(r).display().to_string()),
            vec![NamedInput::file(&evo.join(e).display().to_string())],
        );
        c.text.kitti_times = Some(evo.join("KITTI_00_gt_times.txt"));
        (format!("{r} / {e}"), c)
    };
    let topics = |file: &str, r: &str, e: &[&str]| {
        (
            format!("{file} {r} / {e:?}"),
            EvalConfig::new(
                Some(evo.join(file)),
                NamedInput::topic(r),
                e.iter().map(|e| NamedInput::topic(e)).collect(),
            ),
        )
    };
    let cases = [
        files("V102_groundtruth.csv", "V102.txt"),
        files(
            "freiburg1_xyz-groundtruth.txt",
            "freiburg1_xyz-rgbdslam.txt",
        ),
        files("fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt"),
        files("KITTI_00_gt.txt", "KITTI_00_ORB.txt"),
        files("KITTI_00_gt.txt", "KITTI_00_SPTAM.txt"),
        topics("ROS_example.bag", "groundtruth", &["ORB-SLAM", "S-PTAM"]),
        topics("nav2_turtlebot.mcap", "/amcl_pose", &["/odom"]),
        topics("nav2_turtlebot.mcap", "/tf:map:base_footprint", &["/odom"]),
    ];
    for (name, c) in cases {
        let rep = evaluate(&c).unwrap_or_else(|e| panic!("{name}: {e}"));
        for e in &rep.estimates {
            let o = &e.time_offset;
            println!(
                "{name} {}: Δt {:+.4} ± {} s, status {}, model {:?}: {}",
                e.name,
                o.offset_s,
                o.sigma_s.map_or("-".into(), |s| format!("{s:.4}")),
                o.status,
                o.model,
                o.model_reason.clone().unwrap_or_default()
            );
            assert!(
                o.model.is_none() || o.model == Some(OffsetModel::Constant),
                "{name}: {:?}",
                o.model_reason
            );
        }
        assert!(!has_clock_warning(&rep), "{name}: {:?}", rep.warnings);
    }
}

/// The shifts `real_runs_shifted_move_the_offset_by_the_shift` moves each real estimate's stamps by,
/// seconds: back and forth, a few frames and a few seconds (the clock offsets of unsynchronised
/// recorders), none a whole number of any run's sample periods (the samples do not line up again).
const REAL_SHIFTS_S: [f64; 3] = [-0.7513, 0.4127, 1.9031];

/// Acceptance: a real run's estimate with every stamp moved by a known shift s comes back with its
/// clock offset moved by exactly −s (the estimate's stamps plus Δt are the reference's clock), to
/// within 10 ms, still one constant clock and no clock warning. The runs of
/// `real_recordings_are_constant` from their text files and recordings, read once each; only the
/// estimate's stamps differ between the evaluations, so what the test measures is whether the
/// offset follows the data and not the stamps' origin or the search's grid.
#[test]
fn real_runs_shifted_move_the_offset_by_the_shift() {
    let Some(shared) = common::shared() else {
        return;
    };
    let evo = shared.join("evo-data");
    let mut options = ReadOptions::default();
    options.text.kitti_times = Some(evo.join("KITTI_00_gt_times.txt"));
    let file = |f: &str| {
        read(&[evo.join(f)], None, &options)
            .unwrap_or_else(|e| panic!("{f}: {e}"))
            .named()
    };
    let topic = |rec: &str, t: &str| {
        read(&[evo.join(rec)], Some(t), &options)
            .unwrap_or_else(|e| panic!("{rec} {t}: {e}"))
            .named()
    };
    let runs = [
        ("V102", file("V102_groundtruth.csv"), file("V102.txt")),
        (
            "fr1_xyz",
            file("freiburg1_xyz-groundtruth.txt"),
            file("freiburg1_xyz-rgbdslam.txt"),
        ),
        (
            "fr2_desk",
            file("fr2_desk_groundtruth.txt"),
            file("fr2_desk_ORB.txt"),
        ),
        (
            "KITTI 00 ORB",
            file("KITTI_00_gt.txt"),
            file("KITTI_00_ORB.txt"),
        ),
        (
            "KITTI 00 S-PTAM",
            file("KITTI_00_gt.txt"),
            file("KITTI_00_SPTAM.txt"),
        ),
        (
            "ROS example ORB-SLAM",
            topic("ROS_example.bag", "groundtruth"),
            topic("ROS_example.bag", "ORB-SLAM"),
        ),
        (
            "ROS example S-PTAM",
            topic("ROS_example.bag", "groundtruth"),
            topic("ROS_example.bag", "S-PTAM"),
        ),
        (
            "nav2 amcl / odom",
            topic("nav2_turtlebot.mcap", "/amcl_pose"),
            topic("nav2_turtlebot.mcap", "/odom"),
        ),
    ];
    for (name, reference, estimate) in runs {
        let offset = |shift_s: f64| {
            let mut moved = estimate.clone();
            moved.trajectory = moved.trajectory.shifted((shift_s * 1e9).round() as i64);
            let rep = evaluate_trajectories(reference.clone(), vec![moved], &Parameters::default())
                .unwrap_or_else(|e| panic!("{name} shifted {shift_s:+} s: {e}"));
            let o = &rep.estimates[0].time_offset;
            assert!(
                o.model.is_none() || o.model == Some(OffsetModel::Constant),
                "{name} shifted {shift_s:+} s: {:?}",
                o.model_reason
            );
            assert!(
                !has_clock_warning(&rep),
                "{name} shifted {shift_s:+} s: {:?}",
                rep.warnings
            );
            o.offset_s
        };
        let base_s = offset(0.0);
        for shift_s in REAL_SHIFTS_S {
            let moved_s = offset(shift_s);
            println!(
                "{name}: Δt {base_s:+.4} s; stamps {shift_s:+} s → Δt {moved_s:+.4} s, moved {:+.2} ms from −shift",
                1e3 * (base_s - moved_s - shift_s)
            );
            assert!(
                (base_s - moved_s - shift_s).abs() <= 0.010,
                "{name}: stamps moved {shift_s:+} s, Δt {base_s:+.4} → {moved_s:+.4} s"
            );
        }
    }
}

/// The offset stage on the two-hour bench mission (60 laps): the whole-mission search, then what came
/// after it before the offset profile and the clock model (the clock drift's 2 thirds × (1 + 16
/// noise-injected) searches over ±2 s, replayed here with the same parameters) against the profile
/// and model that replace it. Both run in this process, under the same load. Run with
/// `cargo test --release --test it -- --ignored --nocapture time_offset_profile::offset_stage_timing`.
#[test]
#[ignore]
fn offset_stage_timing() {
    use std::time::Instant;
    let m = simulate(&MissionConfig::default(), &laps(121.0));
    let (rt, rp, et, ep) = series(&m);
    let params = OffsetParams::default();
    let start = Instant::now();
    let a = auto_time_offset(&rt, &rp, &et, &ep, &params).unwrap();
    let search = start.elapsed().as_secs_f64();
    // Before: each third searched once and 16 more times with noise (grid 5 ms), ±2 s.
    let start = Instant::now();
    let third = (rt[rt.len() - 1] - rt[0]) / 3.0;
    let p = OffsetParams {
        max_offset_s: 2.0,
        ..params
    };
    let coarse = OffsetParams { grid_s: 0.005, ..p };
    for (lo, hi) in [
        (rt[0], rt[0] + third),
        (rt[rt.len() - 1] - third, rt[rt.len() - 1]),
    ] {
        let ri = rt.partition_point(|&t| t < lo)..rt.partition_point(|&t| t <= hi);
        let shifted: Vec<f64> = et.iter().map(|t| t + a.estimate.offset_s).collect();
        let ei =
            shifted.partition_point(|&t| t < lo - 6.0)..shifted.partition_point(|&t| t <= hi + 6.0);
        for k in 0..17 {
            let q = if k == 0 { &p } else { &coarse };
            let _ = estimate_time_offset(
                a.estimate.method,
                &rt[ri.clone()],
                &rp[ri.clone()],
                &shifted[ei.clone()],
                &ep[ei.clone()],
                q,
            );
        }
    }
    let thirds = start.elapsed().as_secs_f64();
    let start = Instant::now();
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
    let profile = start.elapsed().as_secs_f64();
    println!(
        "2-hour mission ({:.0} s): whole-mission search {search:.2} s; before: + thirds with noise injection {thirds:.2} s = {:.2} s; now: + profile of {} windows and model {profile:.2} s = {:.2} s ({:?})",
        m.duration_s,
        search + thirds,
        p.windows.len(),
        search + profile,
        model.model
    );
}

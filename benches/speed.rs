//! Speed benchmark: wall time of the library's whole evaluation (read, offset search with every method,
//! Drift Error at 1, 5, 10 and 20 m) on each shared mission, and on a long simulated mission; and
//! the audit of a 2-hour mission of five sources against one evaluation of one of them (the audit's
//! target: at most 3×).
//!
//! `cargo bench --bench speed` (reads `$TRAJDRIFT_SHARED`, default `../shared`).

use std::path::PathBuf;
use std::time::Instant;

use trajdrift::evaluate;
use trajdrift::{EvalConfig, NamedInput};

fn main() {
    let shared = std::env::var("TRAJDRIFT_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    for m in [
        "lever_arm",
        "gnss_outages",
        "legged",
        "legged_spins",
        "straight",
    ] {
        let rec = shared.join("fixtures").join(m).join("mission.mcap");
        if !rec.exists() {
            eprintln!("speed: {} missing, skipped", rec.display());
            continue;
        }
        let mut c = EvalConfig::new(
            Some(rec),
            NamedInput::topic("/reference/position"),
            vec![NamedInput::topic("/estimate/odom")],
        );
        c.params.window = Some(vec![1.0, 5.0, 10.0, 20.0]);
        let reps = 3;
        let start = Instant::now();
        for _ in 0..reps {
            let r = evaluate(&c);
            if let Err(e) = r {
                eprintln!("speed: {m}: {e}");
            }
        }
        println!(
            "speed: {m:<13} {:8.1} ms per eval",
            start.elapsed().as_secs_f64() * 1e3 / reps as f64
        );
    }
    long_mission();
    audit_of_a_long_mission();
}

/// A two-hour mission (60 laps of the default route: 10 Hz reference, 20 Hz estimate), the length the
/// clock drift is measured for, written to a temporary MCAP and evaluated once with the defaults.
fn long_mission() {
    use trajdrift::simulate::{default_route, simulate, writer::write_mcap, MissionConfig};
    let route: Vec<_> = std::iter::repeat_n(default_route(), 60).flatten().collect();
    let mission = simulate(&MissionConfig::default(), &route);
    let dir = tempfile::tempdir().expect("temporary folder");
    let rec = dir.path().join("long.mcap");
    let file = std::fs::File::create(&rec).expect("temporary file");
    write_mcap(std::io::BufWriter::new(file), &mission, 0).expect("write the mission");
    let mut c = EvalConfig::new(
        Some(rec),
        NamedInput::topic("/reference/position"),
        vec![NamedInput::topic("/estimate/odom")],
    );
    c.params.window = Some(vec![1.0, 5.0, 10.0, 20.0]);
    let start = Instant::now();
    match evaluate(&c) {
        Ok(r) => {
            let o = &r.estimates[0].time_offset;
            println!(
                "speed: 2-hour mission ({:.0} s) {:8.3} s per eval (Δt {:+.4} s, model {:?}, drift {:?} ppm, measured {:?} ± {:?})",
                mission.duration_s,
                start.elapsed().as_secs_f64(),
                o.offset_s,
                o.model,
                o.drift_ppm,
                o.drift_measured_ppm.map(|v| v.round()),
                o.drift_sigma_ppm.map(|v| v.round()),
            );
        }
        Err(e) => eprintln!("speed: 2-hour mission: {e}"),
    }
}

/// The audit of a two-hour mission of five sources on four clocks, as per-sensor bags
/// (`trajdrift simulate DIR --grandtour --multi-clock --seed 11 --duration 7200`), against one
/// evaluation of one of its sources against the reference, both as the command line runs them (a
/// process each), in turn, five times each: the median wall times and their ratio.
fn audit_of_a_long_mission() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let folder = dir.path().join("mission");
    let path = |p: &std::path::Path| p.display().to_string();
    // Each run its own process, as a user runs them (no allocator or page state carried over).
    let run = |args: &[String]| {
        let start = Instant::now();
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_trajdrift"))
            .args(args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status();
        let code = status.ok().and_then(|s| s.code()).unwrap_or(1);
        (code, start.elapsed().as_secs_f64())
    };
    let simulate: Vec<String> = ["simulate", &path(&folder), "--grandtour", "--multi-clock"]
        .into_iter()
        .chain(["--seed", "11", "--duration", "7200"])
        .map(String::from)
        .collect();
    if run(&simulate).0 != 0 {
        eprintln!("speed: audit: the mission could not be simulated");
        return;
    }
    let json = |name: &str| path(&dir.path().join(name));
    let eval: Vec<String> = [
        "eval",
        &path(&folder),
        "--reference",
        "/boxi/ap20/prism_position",
        "--estimate",
        "/anymal/state_estimator/odometry",
        "--quiet",
        "--json",
        &json("e.json"),
    ]
    .into_iter()
    .map(String::from)
    .collect();
    let audit: Vec<String> = [
        "audit",
        &path(&folder),
        "--quiet",
        "--json",
        &json("a.json"),
    ]
    .into_iter()
    .map(String::from)
    .collect();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (mut e, mut a) = (Vec::new(), Vec::new());
    for _ in 0..5 {
        e.push(run(&eval).1);
        a.push(run(&audit).1);
    }
    let (e, a) = (median(e), median(a));
    println!(
        "speed: 2-hour mission, 5 sources: audit {a:.3} s, one eval {e:.3} s: {:.2}× (target ≤ 3×)",
        a / e
    );
}

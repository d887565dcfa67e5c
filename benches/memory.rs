//! Memory benchmark: peak RSS of `trajdrift eval`, and of `eval --annotate` (the annotated copy), on a
//! large recording whose bulk is an unrelated channel (like lidar). The acceptance target: below 5 % of
//! the file size.
//!
//! `cargo bench --bench memory` (size with `TRAJDRIFT_BENCH_MIB`, default 1100 MiB; the recording is
//! written to `target/bench-data/` once and reused). Prints the file size, the child's peak RSS
//! (wait4's rusage of each child, the same figure as `/usr/bin/time -v`'s "Maximum resident set size"),
//! the ratio, and the read throughput.

mod support;

use std::path::PathBuf;
use std::process::Command;

use support::measure;

use trajdrift::simulate::writer::write_mcap;
use trajdrift::simulate::{default_route, simulate, MissionConfig};

fn main() {
    let mib: u64 = std::env::var("TRAJDRIFT_BENCH_MIB")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1100);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("create target/bench-data");
    let path = dir.join(format!("bulk-{mib}mib.mcap"));
    let mission = simulate(&MissionConfig::default(), &default_route());
    if !path.exists() {
        let bulk = (mib as f64 * 1024.0 * 1024.0 / (mission.duration_s * 10.0)) as usize;
        let tmp = path.with_extension("tmp");
        let f =
            std::io::BufWriter::new(std::fs::File::create(&tmp).expect("create bench recording"));
        write_mcap(f, &mission, bulk).expect("write bench recording");
        std::fs::rename(&tmp, &path).expect("rename bench recording");
    }
    let size = std::fs::metadata(&path).expect("stat").len();
    let eval_args = |cmd: &mut Command| {
        cmd.args(["eval", "--quiet", "--platform", "wheeled"])
            .arg(&path)
            .args([
                "--reference",
                "/reference/position",
                "--estimate",
                "/estimate/odom",
                "--json",
            ])
            .arg(dir.join("bulk-report.json"));
    };
    let mut eval = Command::new(env!("CARGO_BIN_EXE_trajdrift"));
    eval_args(&mut eval);
    report("eval", size, measure(eval));

    // The annotated copy: both streaming passes (evaluation, then copy with the new channels).
    let annotated = dir.join("bulk-annotated.mcap");
    let mut annotate = Command::new(env!("CARGO_BIN_EXE_trajdrift"));
    eval_args(&mut annotate);
    annotate.arg("--annotate").arg(&annotated).arg("--force");
    report("eval --annotate", size, measure(annotate));
    let _ = std::fs::remove_file(&annotated);
}

fn report(what: &str, size: u64, (code, peak, secs): (Option<i32>, u64, f64)) {
    println!(
        "memory: {what}: file {:.1} MiB, exit {:?}, peak RSS {:.1} MiB = {:.2} % of the file (target < 5 %), {:.2} s, {:.0} MiB/s",
        size as f64 / 1048576.0,
        code,
        peak as f64 / 1048576.0,
        100.0 * peak as f64 / size as f64,
        secs,
        size as f64 / 1048576.0 / secs
    );
    assert!(code.is_some_and(|c| c == 0 || c == 3), "{what} failed");
    assert!(
        (peak as f64) < 0.05 * size as f64,
        "{what}: peak RSS above 5 % of the file size"
    );
}

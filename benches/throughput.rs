//! Throughput benchmark (evaluating at the speed of reading): how `trajdrift eval` with all
//! defaults compares with the floor, a bare stream of the same recording.
//!
//! `cargo bench --bench throughput` (reads `$TRAJDRIFT_SHARED`, default `../shared`). Prints, from one
//! run:
//! - a 2-hour, 200 Hz simulated recording (60 laps of the default route; 10 Hz PointStamped reference,
//!   200 Hz Odometry estimate; written once to `target/bench-data/`): the floor — the `mcap` crate's
//!   streaming `LinearReader` and `cdr-encoding` decoding both topics into memory, nothing else — and
//!   `trajdrift eval` with all defaults, each in its own child process: wall time, peak RSS (wait4), and
//!   the ratios eval/floor (targets ≤ 1.5× time, ≤ 2× memory); and `eval` once more with glibc's
//!   mmap threshold left dynamic (`TRAJDRIFT_MALLOC_DYNAMIC=1`), what the allocator setting is worth;
//! - `trajdrift eval` with all defaults on each shared 2–8-minute mission (target ≤ 0.15 s);
//! - `trajdrift batch` over 8 missions with `--jobs 1` and `--jobs 2`, and the speed-up (target ≥ 1.7×).
//!
//! The floor is this same binary run again with `TRAJDRIFT_BENCH_FLOOR=FILE`; the recording is
//! written by another run of it (`TRAJDRIFT_BENCH_WRITE=FILE`), so this process stays small: a child's
//! peak RSS counts the parent's memory at the fork.

mod support;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use support::measure;
use trajdrift::decode::cdr::decode;
use trajdrift::decode::ros2_msgs::{Odometry, PointStamped};

const FLOOR_VAR: &str = "TRAJDRIFT_BENCH_FLOOR";
const WRITE_VAR: &str = "TRAJDRIFT_BENCH_WRITE";

fn main() {
    if let Ok(path) = std::env::var(FLOOR_VAR) {
        let (r, e) = floor(Path::new(&path));
        println!("{r} {e}");
        return;
    }
    if let Ok(path) = std::env::var(WRITE_VAR) {
        write_long_recording(Path::new(&path));
        return;
    }
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("create target/bench-data");
    let long = long_recording(&dir);
    ratio(&long, &dir);
    let shared = std::env::var("TRAJDRIFT_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    short_missions(&shared);
    batch_scaling(&shared, &dir);
}

/// The 2-hour, 200 Hz recording, written once (by a child: see the module's doc).
fn long_recording(dir: &Path) -> PathBuf {
    let path = dir.join("two-hours-200hz.mcap");
    if !path.exists() {
        let status = Command::new(std::env::current_exe().expect("this bench's path"))
            .env(WRITE_VAR, &path)
            .status()
            .expect("run the writer");
        assert!(status.success(), "writing the bench recording failed");
    }
    path
}

fn write_long_recording(path: &Path) {
    use trajdrift::simulate::{default_route, simulate, writer::write_mcap, MissionConfig};
    let route: Vec<_> = std::iter::repeat_n(default_route(), 60).flatten().collect();
    let config = MissionConfig {
        est_rate_hz: 200.0,
        ..MissionConfig::default()
    };
    let mission = simulate(&config, &route);
    let tmp = path.with_extension("tmp");
    let file = std::fs::File::create(&tmp).expect("create the bench recording");
    write_mcap(std::io::BufWriter::new(file), &mission, 0).expect("write the bench recording");
    std::fs::rename(&tmp, path).expect("rename the bench recording");
}

/// The floor: stream `path` with the bare `mcap` crate and decode both topics into memory. Returns the
/// numbers of reference and estimate samples kept.
fn floor(path: &Path) -> (usize, usize) {
    use mcap::records::Record;
    use mcap::sans_io::{LinearReadEvent, LinearReader};
    let mut file = std::fs::File::open(path).expect("open");
    let mut reader = LinearReader::new();
    let mut topics: std::collections::HashMap<u16, String> = Default::default();
    let mut reference: Vec<(i64, [f64; 3])> = Vec::new();
    let mut estimate: Vec<(i64, [f64; 3], [f64; 4])> = Vec::new();
    while let Some(event) = reader.next_event() {
        match event.expect("read the recording") {
            LinearReadEvent::ReadRequest(n) => {
                let buf = reader.insert(n.max(256 * 1024));
                let got = file.read(buf).expect("read");
                reader.notify_read(got);
            }
            LinearReadEvent::Record { data, opcode } => {
                match mcap::parse_record(opcode, data).expect("parse") {
                    Record::Channel(c) => {
                        topics.insert(c.id, c.topic.to_string());
                    }
                    Record::Message { header, data } => {
                        match topics.get(&header.channel_id).map(String::as_str) {
                            Some("/reference/position") => {
                                let m: PointStamped = decode(&data).expect("PointStamped");
                                let p = m.point;
                                reference.push((m.header.stamp.to_ns(), [p.x, p.y, p.z]));
                            }
                            Some("/estimate/odom") => {
                                let m: Odometry = decode(&data).expect("Odometry");
                                let (p, q) = (m.pose.pose.position, m.pose.pose.orientation);
                                estimate.push((
                                    m.header.stamp.to_ns(),
                                    [p.x, p.y, p.z],
                                    [q.x, q.y, q.z, q.w],
                                ));
                            }
                            _ => {}
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    (reference.len(), estimate.len())
}

fn eval_command(recording: &Path) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_trajdrift"));
    cmd.arg("eval")
        .arg(recording)
        .args(["--reference", "/reference/position"])
        .args(["--estimate", "/estimate/odom", "--quiet"]);
    cmd
}

/// The floor and `eval` on the long recording, side by side.
fn ratio(long: &Path, dir: &Path) {
    let size = std::fs::metadata(long).map_or(0, |m| m.len()) as f64 / 1048576.0;
    let mut floor_cmd = Command::new(std::env::current_exe().expect("this bench's path"));
    floor_cmd.env(FLOOR_VAR, long);
    let (fc, fmem, fsecs) = measure(floor_cmd);
    let mut eval = eval_command(long);
    eval.arg("--json").arg(dir.join("two-hours-report.json"));
    let (ec, emem, esecs) = measure(eval);
    let mib = |b: u64| b as f64 / 1048576.0;
    println!("throughput: 2-hour 200 Hz recording, {size:.0} MiB");
    println!(
        "throughput:   floor (mcap LinearReader + cdr decode): {fsecs:6.2} s, peak RSS {:6.1} MiB (exit {fc:?})",
        mib(fmem)
    );
    println!(
        "throughput:   trajdrift eval, all defaults:           {esecs:6.2} s, peak RSS {:6.1} MiB (exit {ec:?})",
        mib(emem)
    );
    println!(
        "throughput:   ratio eval/floor: time {:.2}× (target ≤ 1.5×), memory {:.2}× (target ≤ 2×)",
        esecs / fsecs,
        emem as f64 / fmem as f64
    );
    // The same without the allocator setting of src/cli/allocator.rs (what it is worth).
    let mut dynamic = eval_command(long);
    dynamic.env(DYNAMIC_VAR, "1");
    let (dc, dmem, dsecs) = measure(dynamic);
    println!(
        "throughput:   eval with glibc's dynamic mmap threshold ({DYNAMIC_VAR}=1): {dsecs:6.2} s, peak RSS {:6.1} MiB (exit {dc:?})",
        mib(dmem)
    );
}

/// Leaves glibc's mmap threshold dynamic (see src/cli/allocator.rs).
const DYNAMIC_VAR: &str = "TRAJDRIFT_MALLOC_DYNAMIC";

const SHORT: [&str; 5] = [
    "lever_arm",
    "gnss_outages",
    "legged",
    "legged_spins",
    "straight",
];

/// `eval` with all defaults on each shared short mission (the process, start to end).
fn short_missions(shared: &Path) {
    for m in SHORT {
        let rec = shared.join("fixtures").join(m).join("mission.mcap");
        if !rec.exists() {
            eprintln!("throughput: {} missing, skipped", rec.display());
            continue;
        }
        let (code, mem, secs) = measure(eval_command(&rec));
        println!(
            "throughput: {m:<13} eval {:6.3} s (target ≤ 0.15 s), peak RSS {:5.1} MiB, exit {code:?}",
            secs,
            mem as f64 / 1048576.0
        );
    }
}

/// `batch` over 8 missions (the shared fixtures, two of them twice) with one and with two jobs.
fn batch_scaling(shared: &Path, dir: &Path) {
    let mut text = String::new();
    let names = SHORT
        .iter()
        .chain(&["clock_step", "clock_drift", "lever_arm"]);
    for (i, m) in names.enumerate() {
        let rec = shared.join("fixtures").join(m).join("mission.mcap");
        if !rec.exists() {
            eprintln!("throughput: {} missing, batch skipped", rec.display());
            return;
        }
        text.push_str(&format!(
            "[[mission]]\nname = \"m{i}-{m}\"\nrecording = \"{}\"\nreference = \"/reference/position\"\nestimates = [\"/estimate/odom\"]\n\n",
            rec.display()
        ));
    }
    let manifest = dir.join("throughput-missions.toml");
    std::fs::write(&manifest, text).expect("write the manifest");
    let run = |jobs: &str| {
        let out = dir.join(format!("throughput-batch-{jobs}"));
        let _ = std::fs::remove_dir_all(&out);
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_trajdrift"));
        cmd.arg("batch")
            .arg(&manifest)
            .args(["--jobs", jobs, "--quiet", "--out"])
            .arg(&out);
        measure(cmd).2
    };
    let (one, two) = (run("1"), run("2"));
    println!(
        "throughput: batch of 8 missions: --jobs 1 {one:.2} s, --jobs 2 {two:.2} s, speed-up {:.2}× (target ≥ 1.7×)",
        one / two
    );
}

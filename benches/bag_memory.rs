//! Memory benchmark for ROS 1 bags: peak RSS of `trajdrift eval` on a small and a large bag (same
//! mission, the bulk an unrelated 10 Hz channel standing for camera images). Peak memory must not
//! grow with the bag: the large one may use at most a few MiB more than the small one. Then the same
//! for a GrandTour-like mission of 3 bags (prism, DLIO, state estimator; each with a bulk point-cloud
//! channel) of the large size in total, evaluated as one mission from its folder: it may use at most
//! a few MiB more than the single large bag (each file is streamed once, one after the other).
//!
//! `cargo bench --bench bag_memory` (large size with `TRAJDRIFT_BENCH_MIB`, default 1100 MiB; the
//! bags are written to `target/bench-data/` once and reused; chunks uncompressed, 768 KiB as
//! rosbag writes them). Prints, per bag, its size, the child's peak RSS (getrusage of the waited
//! child, as `/usr/bin/time -v` reports it) and the read throughput.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use trajdrift::decode::ros1;
use trajdrift::decode::ros2_msgs::{Header, Odometry, Point, PointStamped, Quaternion, Time};
use trajdrift::simulate::{default_route, simulate, Mission, MissionConfig};
use trajdrift::sources::bag::writer::{BagCompression, BagWriter};

fn write_bag(path: &Path, mission: &Mission, bulk_bytes: usize) {
    let tmp = path.with_extension("tmp");
    let f = std::io::BufWriter::new(std::fs::File::create(&tmp).expect("create bench bag"));
    let mut w = BagWriter::new(f, BagCompression::None, 768 * 1024).expect("bag");
    let rc = w.add_connection("/reference/position", "geometry_msgs/PointStamped");
    let ec = w.add_connection("/estimate/odom", "nav_msgs/Odometry");
    let bc = w.add_connection("/camera/raw", "sensor_msgs/Image");
    let mut events: Vec<(i64, u8, usize)> = Vec::new();
    events.extend(
        mission
            .reference
            .stamps_ns
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, 0, i)),
    );
    events.extend(
        mission
            .estimate
            .stamps_ns
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, 1, i)),
    );
    let t0 = mission.config.start_time_ns;
    events.extend(
        (0..(mission.duration_s * 10.0) as usize).map(|i| (t0 + i as i64 * 100_000_000 + 1, 2, i)),
    );
    events.sort();
    let bulk = vec![0x5au8; bulk_bytes];
    for (stamp, kind, i) in events {
        let header = Header {
            stamp: Time::from_ns(stamp),
            frame_id: "map".into(),
        };
        let (conn, data) = match kind {
            0 => {
                let p = mission.reference.positions[i];
                let m = PointStamped {
                    header,
                    point: Point {
                        x: p.x,
                        y: p.y,
                        z: p.z,
                    },
                };
                (rc, ros1::encode_point_stamped(i as u32, &m))
            }
            1 => {
                let p = mission.estimate.positions[i];
                let mut m = Odometry {
                    header,
                    ..Default::default()
                };
                m.pose.pose.position = Point {
                    x: p.x,
                    y: p.y,
                    z: p.z,
                };
                if let Some(q) = mission.estimate.orientations.as_ref().map(|o| o[i]) {
                    m.pose.pose.orientation = Quaternion {
                        x: q.i,
                        y: q.j,
                        z: q.k,
                        w: q.w,
                    };
                }
                (ec, ros1::encode_odometry(i as u32, &m))
            }
            _ => (bc, bulk.clone()),
        };
        w.write(conn, stamp as u64, &data).expect("write bench bag");
    }
    w.finish().expect("finish bench bag");
    std::fs::rename(&tmp, path).expect("rename bench bag");
}

/// Runs eval on `path`; returns (peak RSS bytes, seconds). Each run is measured in its own child
/// so RUSAGE_CHILDREN's maximum is that run's (the larger bag runs last).
fn eval(path: &Path, dir: &Path) -> (u64, f64) {
    eval_topics(path, dir, "/reference/position", "/estimate/odom")
}

/// [`eval`] with the reference and estimate topics given.
fn eval_topics(path: &Path, dir: &Path, reference: &str, estimate: &str) -> (u64, f64) {
    let start = Instant::now();
    let status = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(["eval", "--quiet", "--platform", "wheeled"])
        .arg(path)
        .args(["--reference", reference, "--estimate", estimate, "--json"])
        .arg(dir.join("bag-report.json"))
        .status()
        .expect("run trajdrift eval");
    let secs = start.elapsed().as_secs_f64();
    assert!(
        status.code().is_some_and(|c| c == 0 || c == 3),
        "eval failed"
    );
    // SAFETY: getrusage only writes into the struct we pass.
    let maxrss_kib = unsafe {
        let mut ru: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru);
        ru.ru_maxrss as u64
    };
    (maxrss_kib * 1024, secs)
}

fn main() {
    let mib: u64 = std::env::var("TRAJDRIFT_BENCH_MIB")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1100);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("create target/bench-data");
    let mission = simulate(&MissionConfig::default(), &default_route());
    let mut peaks = Vec::new();
    for m in [64, mib] {
        let path = dir.join(format!("bulk-{m}mib.bag"));
        if !path.exists() {
            let bulk = (m as f64 * 1048576.0 / (mission.duration_s * 10.0)) as usize;
            write_bag(&path, &mission, bulk);
        }
        let size = std::fs::metadata(&path).expect("stat").len();
        let (peak, secs) = eval(&path, &dir);
        println!(
            "bag memory: file {:.1} MiB, peak RSS {:.1} MiB, {:.2} s, {:.0} MiB/s",
            size as f64 / 1048576.0,
            peak as f64 / 1048576.0,
            secs,
            size as f64 / 1048576.0 / secs
        );
        peaks.push(peak);
    }
    let growth = peaks[1] as f64 - peaks[0] as f64;
    println!(
        "bag memory: growth small → large {:.1} MiB",
        growth / 1048576.0
    );
    assert!(growth < 8.0 * 1048576.0, "peak memory grows with the bag");
    let (size, peak, secs) = grandtour_mission(&dir, &mission, mib);
    println!(
        "bag memory: 3-bag mission {:.1} MiB, peak RSS {:.1} MiB, {:.2} s, {:.0} MiB/s; vs the single {mib} MiB bag {:+.1} MiB",
        size as f64 / 1048576.0,
        peak as f64 / 1048576.0,
        secs,
        size as f64 / 1048576.0 / secs,
        (peak as f64 - peaks[1] as f64) / 1048576.0
    );
    assert!(
        (peak as f64) < peaks[1] as f64 + 8.0 * 1048576.0,
        "a mission of 3 bags needs more memory than one bag of the same size"
    );
}

/// Writes (once) and evaluates a GrandTour-like mission of 3 bags, `mib` MiB in all; returns its
/// size, peak RSS and seconds.
fn grandtour_mission(dir: &Path, mission: &Mission, mib: u64) -> (u64, u64, f64) {
    use trajdrift::simulate::grandtour::{
        write_grandtour, GrandTourBag, GrandTourOptions, DLIO_TOPIC, PRISM_TOPIC,
    };
    let folder = dir.join(format!("grandtour-3bags-{mib}mib"));
    if !folder.exists() {
        let bags = vec![
            GrandTourBag::Prism,
            GrandTourBag::Dlio,
            GrandTourBag::StateEstimator,
        ];
        let per_message = mib as f64 * 1048576.0 / (mission.duration_s * 10.0 * bags.len() as f64);
        let tmp = dir.join(format!("grandtour-3bags-{mib}mib.tmp"));
        let _ = std::fs::remove_dir_all(&tmp);
        let options = GrandTourOptions {
            bags,
            bulk_bytes: per_message as usize,
            merged: false,
        };
        write_grandtour(&tmp, mission, &options).expect("write the mission");
        std::fs::rename(&tmp, &folder).expect("rename the mission");
    }
    let size = trajdrift::sources::open::input_size(&folder);
    let (peak, secs) = eval_topics(&folder, dir, PRISM_TOPIC, DLIO_TOPIC);
    (size, peak, secs)
}

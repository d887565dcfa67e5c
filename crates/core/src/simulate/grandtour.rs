//! A simulated mission written the way GrandTour distributes its missions: one ROS 1 bag per sensor
//! group, all on one time base, named `<stamp>_<group>.bag`, with GrandTour's topic names and frames
//! (`trajdrift simulate OUT_DIR --grandtour`), or the same messages merged into one bag (`--merged`),
//! so tests can check that a mission read from its files gives what one merged recording gives.
//!
//! | file | topic | type | frames |
//! |---|---|---|---|
//! | `_cpt7_ie_tc.bag` | `/boxi/inertial_explorer/tc/odometry` | `nav_msgs/Odometry` | `enu_origin` → `cpt7_imu` |
//! | `_ap20_prism_position.bag` | `/boxi/ap20/prism_position` | `geometry_msgs/PointStamped` | `leica_total_station` |
//! | `_dlio.bag` | `/boxi/dlio/lidar_map_odometry`, `/tf` | `nav_msgs/Odometry`, `tf2_msgs/TFMessage` | `dlio_map` → `hesai_lidar`; `/tf` `dlio_map` → `base` |
//! | `_anymal_state.bag` | `/anymal/state_estimator/odometry` | `nav_msgs/Odometry` | `odom` → `base` |
//! | `_tf_minimal.bag` | `/tf_static` | `tf2_msgs/TFMessage` | `base` → `hesai_lidar`, `prism`, `cpt7_imu` |
//!
//! The INS and the prism carry the simulated reference (the reference sensor's positions); DLIO is the
//! simulated estimate (the estimate sensor, `hesai_lidar`, in its own map frame); the state estimator
//! is the body (`base`) in `odom`, the same motion one lever arm away. The `/tf` edge `dlio_map → base`
//! and the static `base → hesai_lidar` compose, across two bags, into the DLIO pose again
//! (`/tf:dlio_map:hesai_lidar`). `bulk_bytes` adds a 10 Hz `sensor_msgs/PointCloud2` channel to every
//! sensor bag (what a memory benchmark needs: large files whose bulk we must skip).
//!
//! [`write_multi_clock`] (`--grandtour --multi-clock`) writes a mission of several sources on several
//! clocks instead ([`crate::simulate::sources`]): the prism as reference and the INS, DLIO, the state
//! estimator and open3d_slam (`_open3d_slam.bag`, `/open3d_slam/odometry`) each in its own bag on its
//! own clock, what `trajdrift audit` and `trajdrift restamp` are tested on.

use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::decode::ros1::{self, Writer as Ros1Writer};
use crate::decode::ros2_msgs::{
    Header, Odometry, Point, PointStamped, Quaternion, TFMessage, Time, Transform, TransformStamped,
};
use crate::error::{Error, Result};
use crate::simulate::ros1_definitions::{definition, md5sum};
use crate::simulate::Mission;
use crate::sources::bag::writer::{BagCompression, BagWriter};
use crate::trajectory::Trajectory;

pub use crate::simulate::topics::{
    DLIO_TOPIC, INS_TOPIC, OPEN3D_SLAM_TOPIC, PRISM_TOPIC, STATE_ESTIMATOR_TOPIC,
};

/// The bulk channel (`bulk_bytes` > 0).
pub const BULK_TOPIC: &str = "/boxi/hesai/points";
/// The TF chain that composes the `/tf` edge of `_dlio.bag` with `/tf_static` of `_tf_minimal.bag`.
pub const DLIO_TF_CHAIN: &str = "/tf:dlio_map:hesai_lidar";
/// File name prefix: the mission's start, as GrandTour names its bags.
pub const STAMP: &str = "2024-06-15-14-00-00";

/// One bag of the layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GrandTourBag {
    Ins,
    Prism,
    Dlio,
    StateEstimator,
    TfMinimal,
    /// open3d_slam's bag, in the multi-clock layout ([`write_multi_clock`]).
    Open3dSlam,
}

impl GrandTourBag {
    /// Every bag of the layout.
    pub const ALL: [GrandTourBag; 5] = [
        GrandTourBag::Ins,
        GrandTourBag::Prism,
        GrandTourBag::Dlio,
        GrandTourBag::StateEstimator,
        GrandTourBag::TfMinimal,
    ];

    /// The file name, e.g. `2024-06-15-14-00-00_dlio.bag`.
    pub fn file_name(self) -> String {
        let group = match self {
            GrandTourBag::Ins => "cpt7_ie_tc",
            GrandTourBag::Prism => "ap20_prism_position",
            GrandTourBag::Dlio => "dlio",
            GrandTourBag::StateEstimator => "anymal_state",
            GrandTourBag::TfMinimal => "tf_minimal",
            GrandTourBag::Open3dSlam => "open3d_slam",
        };
        format!("{STAMP}_{group}.bag")
    }
}

/// How to write the layout.
#[derive(Debug, Clone)]
pub struct GrandTourOptions {
    /// Which bags (default: all).
    pub bags: Vec<GrandTourBag>,
    /// Bytes of each 10 Hz bulk message in every sensor bag; 0 for none.
    pub bulk_bytes: usize,
    /// Write every bag's messages into one `<stamp>_merged.bag` instead.
    pub merged: bool,
}

impl Default for GrandTourOptions {
    fn default() -> Self {
        GrandTourOptions {
            bags: GrandTourBag::ALL.to_vec(),
            bulk_bytes: 0,
            merged: false,
        }
    }
}

/// One message to write, with the bag it belongs to.
struct Message {
    time: i64,
    bag: GrandTourBag,
    topic: &'static str,
    type_name: &'static str,
    data: Vec<u8>,
}

fn quaternion(q: &UnitQuaternion<f64>) -> Quaternion {
    Quaternion {
        x: q.i,
        y: q.j,
        z: q.k,
        w: q.w,
    }
}

fn point(v: &Vector3<f64>) -> Point {
    Point {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn header(stamp: i64, frame: &str) -> Header {
    Header {
        stamp: Time::from_ns(stamp),
        frame_id: frame.into(),
    }
}

fn odometry(seq: u32, stamp: i64, frame: &str, child: &str, pose: &Isometry3<f64>) -> Vec<u8> {
    let mut m = Odometry {
        header: header(stamp, frame),
        child_frame_id: child.into(),
        ..Default::default()
    };
    m.pose.pose.position = point(&pose.translation.vector);
    m.pose.pose.orientation = quaternion(&pose.rotation);
    ros1::encode_odometry(seq, &m)
}

fn transform(stamp: i64, parent: &str, child: &str, pose: &Isometry3<f64>) -> TransformStamped {
    TransformStamped {
        header: header(stamp, parent),
        child_frame_id: child.into(),
        transform: Transform {
            translation: point(&pose.translation.vector),
            rotation: quaternion(&pose.rotation),
        },
    }
}

/// Every non-bulk message of the mission, in time order (the static transforms first).
fn messages(mission: &Mission) -> Vec<Message> {
    let c = &mission.config;
    let lever = |l: [f64; 3]| {
        Isometry3::from_parts(
            Translation3::new(l[0], l[1], l[2]),
            UnitQuaternion::identity(),
        )
    };
    let (est_lever, ref_lever) = (lever(c.est_lever_m), lever(c.ref_lever_m));
    let mut out = vec![static_transforms(c.start_time_ns, &est_lever, &ref_lever)];
    push_reference(&mut out, &mission.reference);
    push_estimate(&mut out, &mission.estimate, &est_lever);
    // Stable: messages of one stamp keep the order they were pushed in.
    out.sort_by_key(|m| m.time);
    out
}

/// `_tf_minimal.bag`'s `/tf_static` at `t0`: the base to the lidar (the estimate's sensor), the prism
/// and the INS (both at the reference's lever).
fn static_transforms(t0: i64, est_lever: &Isometry3<f64>, ref_lever: &Isometry3<f64>) -> Message {
    Message {
        time: t0,
        bag: GrandTourBag::TfMinimal,
        topic: "/tf_static",
        type_name: "tf2_msgs/TFMessage",
        data: ros1::encode_tf_message(
            0,
            &TFMessage {
                transforms: vec![
                    transform(t0, "base", "hesai_lidar", est_lever),
                    transform(t0, "base", "prism", ref_lever),
                    transform(t0, "base", "cpt7_imu", ref_lever),
                ],
            },
        ),
    }
}

/// The reference's samples, each twice: the INS odometry and the prism position.
fn push_reference(out: &mut Vec<Message>, reference: &Trajectory) {
    for (i, (&t, p)) in reference
        .stamps_ns
        .iter()
        .zip(&reference.positions)
        .enumerate()
    {
        let pose = Isometry3::from_parts(Translation3::from(*p), UnitQuaternion::identity());
        out.push(Message {
            time: t,
            bag: GrandTourBag::Ins,
            topic: INS_TOPIC,
            type_name: "nav_msgs/Odometry",
            data: odometry(i as u32, t, "enu_origin", "cpt7_imu", &pose),
        });
        out.push(Message {
            time: t,
            bag: GrandTourBag::Prism,
            topic: PRISM_TOPIC,
            type_name: "geometry_msgs/PointStamped",
            data: ros1::encode_point_stamped(
                i as u32,
                &PointStamped {
                    header: header(t, "leica_total_station"),
                    point: point(p),
                },
            ),
        });
    }
}

/// The estimate's samples, each three times: DLIO's lidar odometry, its `/tf` edge to the base
/// (`est_lever` away) and the state estimator's base odometry.
fn push_estimate(out: &mut Vec<Message>, estimate: &Trajectory, est_lever: &Isometry3<f64>) {
    let orientations = estimate.orientations.as_deref().unwrap_or(&[]);
    for (i, (&t, p)) in estimate
        .stamps_ns
        .iter()
        .zip(&estimate.positions)
        .enumerate()
    {
        let q = orientations
            .get(i)
            .copied()
            .unwrap_or_else(UnitQuaternion::identity);
        let lidar = Isometry3::from_parts(Translation3::from(*p), q);
        let base = lidar * est_lever.inverse();
        out.push(Message {
            time: t,
            bag: GrandTourBag::Dlio,
            topic: DLIO_TOPIC,
            type_name: "nav_msgs/Odometry",
            data: odometry(i as u32, t, "dlio_map", "hesai_lidar", &lidar),
        });
        out.push(Message {
            time: t,
            bag: GrandTourBag::Dlio,
            topic: "/tf",
            type_name: "tf2_msgs/TFMessage",
            data: ros1::encode_tf_message(
                i as u32,
                &TFMessage {
                    transforms: vec![transform(t, "dlio_map", "base", &base)],
                },
            ),
        });
        out.push(Message {
            time: t,
            bag: GrandTourBag::StateEstimator,
            topic: STATE_ESTIMATOR_TOPIC,
            type_name: "nav_msgs/Odometry",
            data: odometry(i as u32, t, "odom", "base", &base),
        });
    }
}

/// A `sensor_msgs/PointCloud2` of `n` opaque bytes.
fn bulk_message(seq: u32, stamp: i64, n: usize) -> Vec<u8> {
    let mut w = Ros1Writer::default();
    w.header(seq, &header(stamp, "hesai_lidar"))
        .u32(1)
        .u32(n as u32)
        .u32(0);
    w.out.push(0);
    w.u32(1).u32(n as u32).u32(n as u32);
    // Cheap pseudo-random bytes (a real point cloud does not compress to nothing either).
    let mut x = (u64::from(seq) + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    w.out.extend((0..n).map(|_| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x as u8
    }));
    w.out.push(1);
    w.out
}

/// Writes `messages` of `bags` (plus the bulk channel of each sensor bag) into one bag at `path`,
/// with the one file writer ([`crate::output::OutputFile`]: a temporary file renamed when complete,
/// removed on failure).
fn write_bag(
    path: &Path,
    span: (i64, f64),
    all: &[Message],
    bags: &[GrandTourBag],
    bulk_bytes: usize,
) -> Result<()> {
    let mut target = crate::output::OutputFile::create(path)?;
    let file = target
        .file()
        .try_clone()
        .map_err(|e| Error::output(path, &e))?;
    write_bag_to(std::io::BufWriter::new(file), span, all, bags, bulk_bytes)
        .map_err(|e| Error::output(path, &e))?;
    target.commit()
}

/// `span`: the mission's start (ns) and duration (s), which the bulk channel covers.
fn write_bag_to<W: Write + Seek>(
    out: W,
    (t0, duration_s): (i64, f64),
    all: &[Message],
    bags: &[GrandTourBag],
    bulk_bytes: usize,
) -> std::io::Result<()> {
    let mut w = BagWriter::new(out, BagCompression::None, 768 * 1024)?;
    let mut conns: Vec<(&str, u32)> = Vec::new();
    let mut conn = |w: &mut BagWriter<W>, topic: &'static str, ty: &str| -> u32 {
        if let Some(&(_, c)) = conns.iter().find(|(t, _)| *t == topic) {
            return c;
        }
        let c = w.add_connection_with_definition(topic, ty, &definition(ty), md5sum(ty));
        conns.push((topic, c));
        c
    };
    let sensor_bags = bags
        .iter()
        .filter(|b| **b != GrandTourBag::TfMinimal)
        .count();
    let n_bulk = if bulk_bytes > 0 && sensor_bags > 0 {
        (duration_s * 10.0) as usize * sensor_bags
    } else {
        0
    };
    // Bulk messages interleaved by time, generated as they are written (never all in memory).
    let bulk_time = |k: usize| t0 + (k / sensor_bags.max(1)) as i64 * 100_000_000 + 1;
    let mut k = 0;
    for m in all.iter().filter(|m| bags.contains(&m.bag)) {
        while k < n_bulk && bulk_time(k) <= m.time {
            let c = conn(&mut w, BULK_TOPIC, "sensor_msgs/PointCloud2");
            w.write(
                c,
                bulk_time(k) as u64,
                &bulk_message(k as u32, bulk_time(k), bulk_bytes),
            )?;
            k += 1;
        }
        let c = conn(&mut w, m.topic, m.type_name);
        w.write(c, m.time as u64, &m.data)?;
    }
    while k < n_bulk {
        let c = conn(&mut w, BULK_TOPIC, "sensor_msgs/PointCloud2");
        w.write(
            c,
            bulk_time(k) as u64,
            &bulk_message(k as u32, bulk_time(k), bulk_bytes),
        )?;
        k += 1;
    }
    w.finish()?.flush()
}

/// The bags [`write_grandtour`] writes into `dir` with `options`, in name order (claimed as outputs
/// before anything is written).
pub fn grandtour_files(dir: &Path, options: &GrandTourOptions) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = if options.merged {
        vec![dir.join(format!("{STAMP}_merged.bag"))]
    } else {
        options
            .bags
            .iter()
            .map(|b| dir.join(b.file_name()))
            .collect()
    };
    v.sort();
    v
}

/// Writes `mission` into the folder `dir` (created if missing) as GrandTour-like bags; returns the
/// files written, in name order.
pub fn write_grandtour(
    dir: &Path,
    mission: &Mission,
    options: &GrandTourOptions,
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::output(dir, &e))?;
    let all = messages(mission);
    let span = (mission.config.start_time_ns, mission.duration_s);
    let mut written = Vec::new();
    if options.merged {
        let path = dir.join(format!("{STAMP}_merged.bag"));
        write_bag(&path, span, &all, &options.bags, options.bulk_bytes)?;
        written.push(path);
    } else {
        for &bag in &options.bags {
            let path = dir.join(bag.file_name());
            let bulk = if bag == GrandTourBag::TfMinimal {
                0
            } else {
                options.bulk_bytes
            };
            write_bag(&path, span, &all, &[bag], bulk)?;
            written.push(path);
        }
    }
    written.sort();
    Ok(written)
}

/// The bag and message type of each source of a multi-clock mission, by name.
fn multi_clock_bag(name: &str) -> GrandTourBag {
    match name {
        "ins" => GrandTourBag::Ins,
        "dlio" => GrandTourBag::Dlio,
        "state_estimator" => GrandTourBag::StateEstimator,
        _ => GrandTourBag::Open3dSlam,
    }
}

/// The frames a multi-clock source publishes in: (frame, child frame).
fn multi_clock_frames(name: &str) -> (&'static str, &'static str) {
    match name {
        "ins" => ("enu_origin", "cpt7_imu"),
        "dlio" => ("dlio_map", "hesai_lidar"),
        "state_estimator" => ("odom", "base"),
        _ => ("open3d_map", "livox_lidar"),
    }
}

/// The bags of the multi-clock layout ([`write_multi_clock`]), in name order.
pub fn multi_clock_files(dir: &Path, merged: bool) -> Vec<PathBuf> {
    if merged {
        return vec![dir.join(format!("{STAMP}_merged.bag"))];
    }
    let mut v: Vec<PathBuf> = MULTI_CLOCK_BAGS
        .iter()
        .map(|b| dir.join(b.file_name()))
        .collect();
    v.sort();
    v
}

/// The bags of the multi-clock layout.
const MULTI_CLOCK_BAGS: [GrandTourBag; 6] = [
    GrandTourBag::TfMinimal,
    GrandTourBag::Prism,
    GrandTourBag::Ins,
    GrandTourBag::Dlio,
    GrandTourBag::StateEstimator,
    GrandTourBag::Open3dSlam,
];

/// Writes a multi-source mission ([`crate::simulate::sources`]) GrandTour's way: the prism (the
/// reference, on the true clock) in `_ap20_prism_position.bag`, each source in its own bag on its own
/// clock (header stamps and record times both read that clock, as a per-computer recorder writes them):
/// the INS in `_cpt7_ie_tc.bag`, DLIO with its `/tf` edge `dlio_map → base` in `_dlio.bag`, the state
/// estimator in `_anymal_state.bag`, open3d_slam in `_open3d_slam.bag`, and the static levers
/// (`base → hesai_lidar`, `prism`, `cpt7_imu`) in `_tf_minimal.bag`. `merged`: all of it in one
/// `<stamp>_merged.bag`. Returns the files written, in name order.
pub fn write_multi_clock(
    dir: &Path,
    mission: &crate::simulate::sources::MultiClockMission,
    merged: bool,
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::output(dir, &e))?;
    let c = &mission.config;
    let t0 = c.start_time_ns;
    let mut all = vec![multi_clock_static_tf(mission)];
    for (i, (&t, p)) in mission
        .reference
        .stamps_ns
        .iter()
        .zip(&mission.reference.positions)
        .enumerate()
    {
        all.push(Message {
            time: t,
            bag: GrandTourBag::Prism,
            topic: PRISM_TOPIC,
            type_name: "geometry_msgs/PointStamped",
            data: ros1::encode_point_stamped(
                i as u32,
                &PointStamped {
                    header: header(t, "leica_total_station"),
                    point: point(p),
                },
            ),
        });
    }
    for (spec, traj) in c.sources.iter().zip(&mission.sources) {
        source_messages(spec, traj, &mut all);
    }
    all.sort_by_key(|m| m.time);
    let span = (t0, mission.duration_s);
    let bags = MULTI_CLOCK_BAGS;
    let mut written = Vec::new();
    if merged {
        let path = dir.join(format!("{STAMP}_merged.bag"));
        write_bag(&path, span, &all, &bags[..], 0)?;
        written.push(path);
    } else {
        for &bag in &bags {
            let path = dir.join(bag.file_name());
            write_bag(&path, span, &all, &[bag], 0)?;
            written.push(path);
        }
    }
    written.sort();
    Ok(written)
}

fn iso(v: Vector3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(v), UnitQuaternion::identity())
}

/// `/tf_static`: the lidar's, the prism's and the INS's place on the body.
fn multi_clock_static_tf(mission: &crate::simulate::sources::MultiClockMission) -> Message {
    let c = &mission.config;
    let t0 = c.start_time_ns;
    let lever_of = |name: &str| {
        c.sources
            .iter()
            .find(|s| s.name == name)
            .map_or(Vector3::zeros(), |s| Vector3::from(s.lever_m))
    };
    Message {
        time: t0,
        bag: GrandTourBag::TfMinimal,
        topic: "/tf_static",
        type_name: "tf2_msgs/TFMessage",
        data: ros1::encode_tf_message(
            0,
            &TFMessage {
                transforms: vec![
                    transform(t0, "base", "hesai_lidar", &iso(lever_of("dlio"))),
                    transform(t0, "base", "prism", &iso(Vector3::zeros())),
                    transform(t0, "base", "cpt7_imu", &iso(lever_of("ins"))),
                ],
            },
        ),
    }
}

/// One source's odometry messages (and DLIO's TF), on its own clock.
fn source_messages(
    spec: &crate::simulate::sources::SourceSpec,
    traj: &crate::trajectory::Trajectory,
    all: &mut Vec<Message>,
) {
    let topic: &'static str = match spec.name.as_str() {
        "ins" => INS_TOPIC,
        "dlio" => DLIO_TOPIC,
        "state_estimator" => STATE_ESTIMATOR_TOPIC,
        _ => OPEN3D_SLAM_TOPIC,
    };
    let bag = multi_clock_bag(&spec.name);
    let (frame, child) = multi_clock_frames(&spec.name);
    let lever = iso(Vector3::from(spec.lever_m));
    let orientations = traj.orientations.as_deref().unwrap_or(&[]);
    for (i, (&t, p)) in traj.stamps_ns.iter().zip(&traj.positions).enumerate() {
        let q = orientations
            .get(i)
            .copied()
            .unwrap_or_else(UnitQuaternion::identity);
        let pose = Isometry3::from_parts(Translation3::from(*p), q);
        all.push(Message {
            time: t,
            bag,
            topic,
            type_name: "nav_msgs/Odometry",
            data: odometry(i as u32, t, frame, child, &pose),
        });
        if spec.name == "dlio" {
            all.push(Message {
                time: t,
                bag,
                topic: "/tf",
                type_name: "tf2_msgs/TFMessage",
                data: ros1::encode_tf_message(
                    i as u32,
                    &TFMessage {
                        transforms: vec![transform(
                            t,
                            "dlio_map",
                            "base",
                            &(pose * lever.inverse()),
                        )],
                    },
                ),
            });
        }
    }
}

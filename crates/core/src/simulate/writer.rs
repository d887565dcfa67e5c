//! Writes a simulated mission as a ROS 2 MCAP recording (profile `ros2`, `ros2msg` schemas, CDR
//! messages, zstd chunks), plus its truth as JSON, so fixtures and benchmarks come from our own code.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use crate::decode::cdr::encode_le;
use crate::decode::ros2_msgs::{
    Header, Odometry, Point, PointStamped, Pose, PoseWithCovariance, Quaternion, Time,
};
use crate::decode::ros2_schemas::schema_text;
use crate::error::{Error, Result};
use crate::simulate::Mission;

/// Topic of the simulated reference (`geometry_msgs/msg/PointStamped`, world ENU).
pub const REFERENCE_TOPIC: &str = "/reference/position";
/// Topic of the simulated estimate (`nav_msgs/msg/Odometry`, its own `odom` frame).
pub const ESTIMATE_TOPIC: &str = "/estimate/odom";
/// An unrelated channel standing for bulk data such as lidar scans or images, written at 10 Hz.
pub const BULK_TOPIC: &str = "/camera/raw";

fn mcap_err(e: mcap::McapError) -> Error {
    Error::Output {
        path: "<mcap>".into(),
        detail: e.to_string(),
    }
}

/// Writes `mission` to `out`. `bulk_bytes` > 0 adds a 10 Hz unrelated channel of messages that size
/// (what a memory benchmark needs: a large file whose bulk we must skip).
///
/// The channels are registered, the messages of all streams put in stamp order (`events`), then
/// each is encoded (`encode_event`) and written with its channel's sequence number.
pub fn write_mcap<W: Write + Seek>(out: W, mission: &Mission, bulk_bytes: usize) -> Result<()> {
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .library(concat!("trajdrift ", env!("CARGO_PKG_VERSION")))
        .compression(Some(mcap::Compression::Zstd))
        .create(out)
        .map_err(mcap_err)?;
    let ref_ch = add_channel(&mut w, REFERENCE_TOPIC, "geometry_msgs/msg/PointStamped")?;
    let est_ch = add_channel(&mut w, ESTIMATE_TOPIC, "nav_msgs/msg/Odometry")?;
    let bulk_ch = if bulk_bytes > 0 {
        let schema = w
            .add_schema("sensor_msgs/msg/Image", "ros2msg", b"# opaque bulk payload")
            .map_err(mcap_err)?;
        Some(
            w.add_channel(schema, BULK_TOPIC, "cdr", &BTreeMap::new())
                .map_err(mcap_err)?,
        )
    } else {
        None
    };
    let channels = [ref_ch, est_ch, bulk_ch.unwrap_or(0)];
    let mut seq = [0u32; 3];
    let mut bulk = vec![0u8; bulk_bytes];
    for (stamp, kind, i) in events(mission, bulk_ch.is_some()) {
        let data = encode_event(mission, (stamp, kind, i), &mut bulk);
        seq[kind as usize] += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channels[kind as usize],
            sequence: seq[kind as usize],
            log_time: stamp as u64,
            publish_time: stamp as u64,
        };
        w.write_to_known_channel(&header, &data).map_err(mcap_err)?;
    }
    w.finish().map_err(mcap_err)?;
    Ok(())
}

/// Registers the `ros2msg` schema of `ty` and a CDR channel of it on `topic`; returns the channel id.
fn add_channel<W: Write + Seek>(w: &mut mcap::Writer<W>, topic: &str, ty: &str) -> Result<u16> {
    let text = schema_text(ty)
        .ok_or_else(|| Error::InvalidArgument(format!("no schema text for {ty}")))?;
    let schema = w
        .add_schema(ty, "ros2msg", text.as_bytes())
        .map_err(mcap_err)?;
    w.add_channel(schema, topic, "cdr", &BTreeMap::new())
        .map_err(mcap_err)
}

/// Every message to write as (stamp, stream, index in the stream), interleaved in stamp order as a
/// recorder would: stream 0 the reference, 1 the estimate, 2 the bulk channel (10 Hz, when `bulk`).
fn events(mission: &Mission, bulk: bool) -> Vec<(i64, u8, usize)> {
    let mut events: Vec<(i64, u8, usize)> = Vec::new();
    events.extend(
        mission
            .reference
            .stamps_ns
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, 0u8, i)),
    );
    events.extend(
        mission
            .estimate
            .stamps_ns
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, 1u8, i)),
    );
    if bulk {
        let t0 = mission.config.start_time_ns;
        events.extend(
            (0..(mission.duration_s * 10.0) as usize)
                .map(|i| (t0 + i as i64 * 100_000_000 + 1, 2u8, i)),
        );
    }
    events.sort();
    events
}

/// The CDR bytes of one event of [`events`]: the reference's `PointStamped`, the estimate's
/// `Odometry`, or `bulk` refilled with pseudo-random bytes.
fn encode_event(mission: &Mission, (stamp, kind, i): (i64, u8, usize), bulk: &mut [u8]) -> Vec<u8> {
    match kind {
        0 => {
            let p = mission.reference.positions[i];
            let msg = PointStamped {
                header: Header {
                    stamp: Time::from_ns(stamp),
                    frame_id: "map".into(),
                },
                point: Point {
                    x: p.x,
                    y: p.y,
                    z: p.z,
                },
            };
            encode_le(&msg)
        }
        1 => {
            let p = mission.estimate.positions[i];
            let q = mission
                .estimate
                .orientations
                .as_ref()
                .map(|o| o[i])
                .unwrap_or_default();
            let msg = Odometry {
                header: Header {
                    stamp: Time::from_ns(stamp),
                    frame_id: "odom".into(),
                },
                child_frame_id: "base_link".into(),
                pose: PoseWithCovariance {
                    pose: Pose {
                        position: Point {
                            x: p.x,
                            y: p.y,
                            z: p.z,
                        },
                        orientation: Quaternion {
                            x: q.i,
                            y: q.j,
                            z: q.k,
                            w: q.w,
                        },
                    },
                    covariance: Default::default(),
                },
                twist: Default::default(),
            };
            encode_le(&msg)
        }
        _ => {
            // Cheap pseudo-random bytes so that compression cannot shrink the bulk away.
            let mut x = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
            for b in bulk.iter_mut() {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                *b = x as u8;
            }
            bulk.to_vec()
        }
    }
}

/// The truth of `mission` as JSON (the same keys as the shared fixtures' `truth.json` where they apply).
pub fn truth_json(mission: &Mission) -> serde_json::Value {
    let c = &mission.config;
    let d: Vec<f64> = (0..3)
        .map(|k| c.est_lever_m[k] - c.ref_lever_m[k])
        .collect();
    serde_json::json!({
        "generator": concat!("trajdrift simulate ", env!("CARGO_PKG_VERSION")),
        "config": c,
        "time_offset": {"dt_true_s": c.time_offset_s,
            "convention": "t_est <- t_est + dt maps estimate stamps onto the reference (true) clock"},
        "lever_arms": {"reference": c.ref_lever_m, "estimate": c.est_lever_m, "estimate_minus_reference": d},
        "estimate_model": {"scale_error": c.scale_error},
        "duration_s": mission.duration_s,
        "path_lengths_m": {"body": mission.body_path_m},
        "topics": {
            REFERENCE_TOPIC: {"type": "geometry_msgs/msg/PointStamped", "count": mission.reference.len()},
            ESTIMATE_TOPIC: {"type": "nav_msgs/msg/Odometry", "count": mission.estimate.len()},
        },
    })
}

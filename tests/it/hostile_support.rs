//! Small recordings for the hostile-input tests and the fuzz seeds: an MCAP (ROS 2, zstd chunks,
//! summary) and a ROS 1 bag (chunks, index) of a few dozen messages each, written by the project's own
//! writers, so that mutants stay small and every reader path is reached.
#![allow(dead_code)]

use std::path::Path;

use trajdrift::decode::ros1;
use trajdrift::decode::ros2_msgs::{Header, Odometry, Point, PointStamped, PoseStamped, Time};
use trajdrift::simulate::writer::write_mcap;
use trajdrift::simulate::{default_route, simulate, MissionConfig};
use trajdrift::sources::bag::writer::{BagCompression, BagWriter};

/// A simulated mission cut to its first `n` samples per trajectory, as MCAP.
pub fn small_mcap(path: &Path, n: usize) {
    let mut mission = simulate(&MissionConfig::default(), &default_route());
    for t in [&mut mission.reference, &mut mission.estimate] {
        t.stamps_ns.truncate(n);
        t.positions.truncate(n);
        if let Some(o) = t.orientations.as_mut() {
            o.truncate(n);
        }
    }
    let f = std::fs::File::create(path).unwrap();
    write_mcap(std::io::BufWriter::new(f), &mission, 0).unwrap();
}

/// A ROS 1 bag of `n` reference points and `n` odometry messages, in `compression`.
pub fn small_bag(path: &Path, compression: BagCompression, n: u32) {
    BagShape {
        compression,
        n,
        ..BagShape::default()
    }
    .write(path);
}

/// How an estimate's topic is written in a [`BagShape`].
#[derive(Clone, Copy, Debug)]
pub enum EstimateMsg {
    Odometry,
    Pose,
}

/// A small ROS 1 bag: the reference's points along x = 0.1·i, y = sin(`wave_rad`·i), z = `z_m`, one
/// every `period_ns`, and each estimate topic holding the same positions (the one bag writer of the
/// tests).
#[derive(Clone, Debug)]
pub struct BagShape<'a> {
    pub compression: BagCompression,
    pub n: u32,
    pub period_ns: i64,
    /// Radians of the sine per sample.
    pub wave_rad: f64,
    pub z_m: f64,
    pub chunk_bytes: usize,
    pub estimates: &'a [(&'a str, EstimateMsg)],
}

impl Default for BagShape<'_> {
    fn default() -> Self {
        BagShape {
            compression: BagCompression::None,
            n: 50,
            period_ns: 100_000_000,
            wave_rad: 0.1,
            z_m: 0.5,
            chunk_bytes: 1024,
            estimates: &[("/estimate/odom", EstimateMsg::Odometry)],
        }
    }
}

impl BagShape<'_> {
    /// Writes the bag to `path`.
    pub fn write(&self, path: &Path) {
        let f = std::fs::File::create(path).unwrap();
        let mut w = BagWriter::new(
            std::io::BufWriter::new(f),
            self.compression.clone(),
            self.chunk_bytes,
        )
        .unwrap();
        let r = w.add_connection("/reference/position", "geometry_msgs/PointStamped");
        let estimates: Vec<(u32, EstimateMsg)> = self
            .estimates
            .iter()
            .map(|&(topic, kind)| {
                let ty = match kind {
                    EstimateMsg::Odometry => "nav_msgs/Odometry",
                    EstimateMsg::Pose => "geometry_msgs/PoseStamped",
                };
                (w.add_connection(topic, ty), kind)
            })
            .collect();
        for i in 0..self.n {
            let ns = 1_700_000_000_000_000_000 + i as i64 * self.period_ns;
            let header = Header {
                stamp: Time::from_ns(ns),
                frame_id: "map".into(),
            };
            let point = Point {
                x: i as f64 * 0.1,
                y: (i as f64 * self.wave_rad).sin(),
                z: self.z_m,
            };
            let ps = PointStamped {
                header: header.clone(),
                point,
            };
            w.write(r, ns as u64, &ros1::encode_point_stamped(i, &ps))
                .unwrap();
            for &(c, kind) in &estimates {
                let bytes = match kind {
                    EstimateMsg::Odometry => {
                        let mut o = Odometry {
                            header: header.clone(),
                            ..Default::default()
                        };
                        o.pose.pose.position = point;
                        ros1::encode_odometry(i, &o)
                    }
                    EstimateMsg::Pose => {
                        let mut pose = PoseStamped {
                            header: header.clone(),
                            ..Default::default()
                        };
                        pose.pose.position = point;
                        ros1::encode_pose_stamped(i, &pose)
                    }
                };
                w.write(c, ns as u64, &bytes).unwrap();
            }
        }
        w.finish().unwrap();
    }
}

//! Small recordings for the hostile-input tests and the fuzz seeds: an MCAP (ROS 2, zstd chunks,
//! summary) and a ROS 1 bag (chunks, index) of a few dozen messages each, written by the project's own
//! writers, so that mutants stay small and every reader path is reached.
#![allow(dead_code)]

use std::path::Path;

use trajdrift::decode::ros1;
use trajdrift::decode::ros2_msgs::{Header, Odometry, Point, PointStamped, Time};
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
    let f = std::fs::File::create(path).unwrap();
    let mut w = BagWriter::new(std::io::BufWriter::new(f), compression, 1024).unwrap();
    let r = w.add_connection("/reference/position", "geometry_msgs/PointStamped");
    let e = w.add_connection("/estimate/odom", "nav_msgs/Odometry");
    for i in 0..n {
        let ns = 1_700_000_000_000_000_000 + i as i64 * 100_000_000;
        let header = Header {
            stamp: Time::from_ns(ns),
            frame_id: "map".into(),
        };
        let point = Point {
            x: i as f64 * 0.1,
            y: (i as f64 * 0.1).sin(),
            z: 0.5,
        };
        let ps = PointStamped {
            header: header.clone(),
            point,
        };
        w.write(r, ns as u64, &ros1::encode_point_stamped(i, &ps))
            .unwrap();
        let mut o = Odometry {
            header,
            ..Default::default()
        };
        o.pose.pose.position = point;
        w.write(e, ns as u64, &ros1::encode_odometry(i, &o))
            .unwrap();
    }
    w.finish().unwrap();
}

//! Hostile inputs at the process boundary (issue 9): outputs that would overwrite an input, parameter
//! values out of range, damaged and truncated recordings, names with control characters, closed pipes,
//! dropped rows, and a seeded mutation test of an MCAP and a bag under a 1 GB address-space limit.

mod hostile_support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use hostile_support::{small_bag, small_mcap};
use trajdrift::sources::bag::writer::BagCompression;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run trajdrift")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes the fuzz seeds (small recordings, messages, text files) into fuzz/corpus/. Run by hand:
/// `cargo test --release --test hostile -- --ignored write_fuzz_seeds`.
#[test]
#[ignore]
fn write_fuzz_seeds() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    let dir = |t: &str| {
        let d = root.join(t);
        std::fs::create_dir_all(&d).unwrap();
        d
    };
    small_mcap(&dir("mcap_source").join("small.mcap"), 20);
    small_bag(&dir("bag_reader").join("none.bag"), BagCompression::None, 10);
    small_bag(&dir("bag_reader").join("lz4.bag"), BagCompression::Lz4, 10);
    small_bag(&dir("bag_reader").join("bz2.bag"), BagCompression::Bz2, 10);
    use trajdrift::decode::cdr::encode_le;
    use trajdrift::decode::ros2_msgs::{Header, Odometry, PointStamped, Time};
    let header = Header {
        stamp: Time::from_ns(1_700_000_000_123_456_789),
        frame_id: "map".into(),
    };
    let ps = PointStamped {
        header: header.clone(),
        ..Default::default()
    };
    let od = Odometry {
        header,
        ..Default::default()
    };
    let cdr = dir("cdr_decode");
    std::fs::write(cdr.join("point.cdr"), encode_le(&ps)).unwrap();
    std::fs::write(cdr.join("odom.cdr"), encode_le(&od)).unwrap();
    std::fs::write(
        cdr.join("point.ros1"),
        trajdrift::decode::ros1::encode_point_stamped(1, &ps),
    )
    .unwrap();
    let tf = dir("tf_decode");
    let edge = trajdrift::decode::ros2_msgs::TransformStamped {
        header: ps.header.clone(),
        child_frame_id: "base_link".into(),
        ..Default::default()
    };
    let msg = trajdrift::decode::ros2_msgs::TFMessage {
        transforms: vec![edge.clone(), edge],
    };
    std::fs::write(tf.join("tf.cdr"), encode_le(&msg)).unwrap();
    std::fs::write(
        tf.join("tf.ros1"),
        trajdrift::decode::ros1::encode_tf_message(1, &msg),
    )
    .unwrap();
    let text = dir("text_readers");
    std::fs::write(
        text.join("tum"),
        b"\x00# t x y z qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.1 0.1 0 0 0 0 0 1\n1.1 0.1 0 0 0 0 0 1\n",
    )
    .unwrap();
    std::fs::write(
        text.join("csv"),
        b"\x01t,x,y,z\n1.0,0,0,0\n1.1,0.1,0,0\n",
    )
    .unwrap();
    std::fs::write(
        text.join("kitti"),
        b"\x021 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0.1 0 1 0 0 0 0 1 0\n",
    )
    .unwrap();
    std::fs::write(
        text.join("euroc"),
        b"\x01#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n1403715523912143104,0,0,0,1,0,0,0\n",
    )
    .unwrap();
}

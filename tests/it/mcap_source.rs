//! The streaming MCAP source against the shared simulated missions (written by Python's `mcap` and
//! `rosbags`, not by us) and against small files written here with `mcap::Writer` in every layout.

use crate::common;
use trajdrift::diag::WarningCode;

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use trajdrift::decode::cdr;
use trajdrift::decode::ros2_msgs::{
    Header, NavSatFix, NavSatStatus, Point, PointStamped, Pose, PoseStamped, Quaternion, Time,
};
use trajdrift::decode::ros2_schemas;
use trajdrift::sources::mcap::McapSource;
use trajdrift::sources::tum::read_tum;
use trajdrift::sources::{ExtractOptions, Extraction, Source, StampSource};
use trajdrift::{Error, Trajectory};

fn origin(truth: &serde_json::Value) -> [f64; 3] {
    let o = &truth["geodetic_origin"];
    [
        o["lat_deg"].as_f64().unwrap(),
        o["lon_deg"].as_f64().unwrap(),
        o["h_m"].as_f64().unwrap(),
    ]
}

fn topics(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

fn extract(path: &Path, names: &[&str], options: &ExtractOptions) -> Extraction {
    McapSource::open(path)
        .unwrap()
        .extract(&topics(names), options, &|_| {})
        .unwrap()
}

/// Same stamps to the nanosecond and positions to `tol` metres.
fn assert_same(a: &Trajectory, b: &Trajectory, tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: sample count");
    assert_eq!(a.stamps_ns, b.stamps_ns, "{what}: stamps");
    let worst = a
        .positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| (p - q).amax())
        .fold(0.0, f64::max);
    assert!(worst <= tol, "{what}: positions differ by {worst} m");
}

const MISSION_TOPICS: [&str; 4] = [
    "/reference/position",
    "/estimate/odom",
    "/reference/fix",
    "/estimate/pose",
];

#[test]
fn missions_match_truth_and_tum() {
    let Some(shared) = common::shared() else {
        return;
    };
    for name in common::MISSIONS {
        let mission = common::mission(&shared, name);
        let truth = common::truth(&shared, name);
        let options = ExtractOptions {
            origin: Some(origin(&truth)),
            ..Default::default()
        };
        let progress_calls = AtomicU64::new(0);
        let source = McapSource::open(&mission.join("mission.mcap")).unwrap();
        let ex = source
            .extract(&topics(&MISSION_TOPICS), &options, &|bytes| {
                assert!(bytes <= source.size_bytes());
                progress_calls.fetch_add(1, Ordering::Relaxed);
            })
            .unwrap();
        assert!(ex.warnings.is_empty(), "{name}: {:?}", ex.warnings);
        assert!(progress_calls.load(Ordering::Relaxed) >= 1);
        assert_eq!(ex.topics.len(), 4);
        for (t, topic) in ex.topics.iter().zip(MISSION_TOPICS) {
            assert_eq!(t.topic, topic);
            let count = truth["topics"][topic]["count"].as_u64().unwrap();
            assert_eq!(t.messages, count, "{name} {topic}: messages");
            assert_eq!(
                t.trajectory.len() as u64,
                count,
                "{name} {topic}: samples ({} invalid, {} duplicate stamps)",
                t.invalid_dropped,
                t.duplicate_stamps
            );
            assert_eq!(
                t.type_name,
                truth["topics"][topic]["type"].as_str().unwrap()
            );
        }
        let reference = read_tum(&mission.join("reference.tum")).unwrap();
        let estimate = read_tum(&mission.join("estimate.tum")).unwrap();
        // TUM files carry 6 decimals: 5e-7 m of rounding.
        assert_same(
            &ex.topics[0].trajectory,
            &reference,
            1e-6,
            &format!("{name} position"),
        );
        assert_same(
            &ex.topics[1].trajectory,
            &estimate,
            1e-6,
            &format!("{name} odom"),
        );
        assert_same(
            &ex.topics[3].trajectory,
            &estimate,
            1e-6,
            &format!("{name} pose"),
        );
        // The fixes are the same samples as /reference/position, through WGS84: agree to 1 mm.
        assert_eq!(ex.topics[2].geodetic_origin, Some(origin(&truth)));
        assert_same(
            &ex.topics[2].trajectory,
            &ex.topics[0].trajectory,
            1e-3,
            &format!("{name} fix→ENU"),
        );
        assert!(ex.topics[3].trajectory.orientations.is_some());
        assert!(ex.topics[0].trajectory.orientations.is_none());
    }
}

#[test]
fn topics_lists_every_channel_with_counts() {
    let Some(shared) = common::shared() else {
        return;
    };
    for name in common::MISSIONS {
        let mission = common::mission(&shared, name);
        let truth = common::truth(&shared, name);
        let source = McapSource::open(&mission.join("mission.mcap")).unwrap();
        let listed = source.topics().unwrap();
        let expected = truth["topics"].as_object().unwrap();
        assert_eq!(listed.len(), expected.len());
        for info in listed {
            let t = &expected[&info.topic];
            assert_eq!(info.type_name, t["type"].as_str().unwrap());
            assert_eq!(info.message_count, t["count"].as_u64().unwrap());
            assert_eq!(info.message_encoding, "cdr");
            assert_eq!(
                info.readable,
                !matches!(info.topic.as_str(), "/tf" | "/imu/data"),
                "{}",
                info.topic
            );
        }
    }
}

#[test]
fn log_stamps_and_default_origin() {
    let Some(shared) = common::shared() else {
        return;
    };
    let mission = common::mission(&shared, "gnss_outages");
    let truth = common::truth(&shared, "gnss_outages");
    let ex = extract(
        &mission.join("mission.mcap"),
        &["/reference/fix", "/estimate/pose"],
        &ExtractOptions {
            stamp: StampSource::Log,
            origin: None,
            ..Default::default()
        },
    );
    // gnss_outages records receipt time as log time: it differs from the header stamps.
    let header = extract(
        &mission.join("mission.mcap"),
        &["/estimate/pose"],
        &ExtractOptions::default(),
    );
    assert_eq!(truth["log_time"], "receipt");
    assert_ne!(
        ex.topics[1].trajectory.stamps_ns,
        header.topics[0].trajectory.stamps_ns
    );
    // Default origin: the first valid fix, which therefore sits at (0, 0, 0).
    let fix = &ex.topics[0];
    let o = fix.geodetic_origin.unwrap();
    assert!((o[0] - 46.78).abs() < 0.01 && (o[1] + 71.27).abs() < 0.01);
    assert!(fix.trajectory.positions[0].norm() < 1e-9);
}

#[test]
fn missing_topic_lists_topics_present() {
    let Some(shared) = common::shared() else {
        return;
    };
    let path = shared.join("fixtures/lever_arm/mission.mcap");
    let err = McapSource::open(&path)
        .unwrap()
        .extract(
            &topics(&["/estimate/pose", "/nope"]),
            &Default::default(),
            &|_| {},
        )
        .unwrap_err();
    match &err {
        Error::TopicNotFound {
            topic, available, ..
        } => {
            assert_eq!(topic, "/nope");
            assert!(available.contains(&"/reference/fix".to_string()));
            assert_eq!(available.len(), 6);
        }
        other => panic!("expected TopicNotFound, got {other}"),
    }
    let text = err.to_string();
    assert!(
        text.contains("/nope") && text.contains("/imu/data"),
        "{text}"
    );
}

#[test]
fn unsupported_type_lists_supported_types() {
    let Some(shared) = common::shared() else {
        return;
    };
    let path = shared.join("fixtures/lever_arm/mission.mcap");
    let err = McapSource::open(&path)
        .unwrap()
        .extract(&topics(&["/imu/data"]), &Default::default(), &|_| {})
        .unwrap_err();
    match &err {
        Error::UnsupportedType {
            topic,
            type_name,
            supported,
            ..
        } => {
            assert_eq!(topic, "/imu/data");
            assert_eq!(type_name, "sensor_msgs/msg/Imu");
            assert_eq!(supported.len(), trajdrift::decode::supported_types().len());
        }
        other => panic!("expected UnsupportedType, got {other}"),
    }
    assert!(err.to_string().contains("geometry_msgs/msg/PoseStamped"));
}

#[test]
fn not_mcap_and_unreadable() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("trajectory.txt");
    std::fs::write(&text, "1.0 0 0 0 0 0 0 1\n").unwrap();
    assert!(matches!(
        McapSource::open(&text),
        Err(Error::NotMcap { .. })
    ));
    let short = dir.path().join("short.mcap");
    std::fs::write(&short, b"\x89MC").unwrap();
    assert!(matches!(
        McapSource::open(&short),
        Err(Error::NotMcap { .. })
    ));
    let missing = dir.path().join("missing.mcap");
    assert!(matches!(McapSource::open(&missing), Err(Error::Io { .. })));
}

#[test]
fn truncated_recording_warns_and_keeps_what_was_read() {
    let Some(shared) = common::shared() else {
        return;
    };
    let src = shared.join("fixtures/lever_arm/mission.mcap");
    let bytes = std::fs::read(&src).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let full = extract(&src, &["/estimate/pose"], &ExtractOptions::default());
    let n_full = full.topics[0].trajectory.len();
    // Cut in the middle of the data section (inside a zstd chunk), and a few bytes after the magic.
    for cut in [bytes.len() / 2, bytes.len() / 3 + 7, 100] {
        let path = dir.path().join(format!("cut_{cut}.mcap"));
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let source = McapSource::open(&path).unwrap();
        let result = source.extract(&topics(&["/estimate/pose"]), &Default::default(), &|_| {});
        if cut == 100 {
            // Cut before the channel was recorded: the damage is named, with its byte offset.
            assert!(
                matches!(result, Err(Error::Damaged { offset: 100, .. })),
                "{result:?}"
            );
            continue;
        }
        let ex = result.unwrap();
        assert_eq!(ex.warnings.len(), 1);
        assert_eq!(ex.warnings[0].code, WarningCode::TruncatedRecording);
        assert!(ex.warnings[0].message.contains(&cut.to_string()));
        assert!(ex.warnings[0].message.contains(&path.display().to_string()));
        let got = &ex.topics[0].trajectory;
        assert!(
            !got.is_empty() && got.len() < n_full,
            "{} of {n_full}",
            got.len()
        );
        // What was read is a prefix of the full recording.
        assert_eq!(
            got.stamps_ns[..],
            full.topics[0].trajectory.stamps_ns[..got.len()]
        );
        // topics() works on it too (no summary: a streaming pass).
        assert_eq!(source.topics().unwrap().len(), 6);
    }
}

// ---------------------------------------------------------------------------------------------
// Files written here.

#[derive(Clone, Copy, Debug)]
enum Layout {
    ChunkedZstd,
    ChunkedLz4,
    ChunkedUncompressed,
    Unchunked,
    NoSummary,
}

fn header(ns: i64) -> Header {
    Header {
        stamp: Time::from_ns(ns),
        frame_id: "map".into(),
    }
}

fn pose(i: i64) -> PoseStamped {
    PoseStamped {
        header: header(1_700_000_000_000_000_000 + i * 20_000_000),
        pose: Pose {
            position: Point {
                x: i as f64 * 0.1,
                y: (i as f64 * 0.05).sin(),
                z: -0.5,
            },
            orientation: Quaternion::default(),
        },
    }
}

/// Writes `n` poses on /pose, `n` points on /point, a NavSatFix topic with one NO_FIX and one NaN, a
/// big unrelated /blob channel, and a JSON channel with a supported schema name.
fn write_mcap(path: &Path, layout: Layout, n: i64, big_endian: bool) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut options = mcap::WriteOptions::new()
        .profile("ros2")
        .chunk_size(Some(4096));
    options = match layout {
        Layout::ChunkedZstd => options.compression(Some(mcap::Compression::Zstd)),
        Layout::ChunkedLz4 => options.compression(Some(mcap::Compression::Lz4)),
        Layout::ChunkedUncompressed => options.compression(None),
        Layout::Unchunked => options.use_chunks(false).compression(None),
        Layout::NoSummary => options
            .compression(Some(mcap::Compression::Zstd))
            .emit_summary_records(false)
            .emit_summary_offsets(false)
            .emit_message_indexes(false),
    };
    let mut w = options.create(file).unwrap();
    let meta = BTreeMap::new();
    let channel = |w: &mut mcap::Writer<_>, ty: &str, topic: &str, enc: &str| {
        let schema = w
            .add_schema(
                ty,
                "ros2msg",
                ros2_schemas::schema_text(ty).unwrap_or("").as_bytes(),
            )
            .unwrap();
        w.add_channel(schema, topic, enc, &meta).unwrap()
    };
    let pose_ch = channel(&mut w, "geometry_msgs/msg/PoseStamped", "/pose", "cdr");
    let point_ch = channel(&mut w, "geometry_msgs/msg/PointStamped", "/point", "cdr");
    let fix_ch = channel(&mut w, "sensor_msgs/msg/NavSatFix", "/fix", "cdr");
    let blob_ch = channel(&mut w, "sensor_msgs/msg/Image", "/blob", "cdr");
    let json_ch = channel(
        &mut w,
        "geometry_msgs/msg/PoseStamped",
        "/json_pose",
        "json",
    );
    let encode = |m: &dyn erased::Encode| if big_endian { m.be() } else { m.le() };
    let blob = vec![0xA5u8; 3000];
    for i in 0..n {
        let t = (1_700_000_000_000_000_000 + i * 20_000_000) as u64;
        let mut put = |ch: u16, data: &[u8]| {
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: i as u32,
                    log_time: t + 1_000,
                    publish_time: t,
                },
                data,
            )
            .unwrap();
        };
        put(pose_ch, &encode(&pose(i)));
        let p = pose(i);
        put(
            point_ch,
            &encode(&PointStamped {
                header: p.header.clone(),
                point: p.pose.position,
            }),
        );
        put(
            fix_ch,
            &encode(&NavSatFix {
                header: p.header,
                status: NavSatStatus {
                    status: if i == 3 { -1 } else { 0 },
                    service: 1,
                },
                latitude: if i == 5 {
                    f64::NAN
                } else {
                    46.78 + i as f64 * 1e-6
                },
                longitude: -71.27,
                altitude: 50.0,
                position_covariance: [0.0; 9],
                position_covariance_type: 0,
            }),
        );
        put(blob_ch, &blob);
        put(json_ch, b"{}");
    }
    w.finish().unwrap();
}

/// Object-safe encoding of the test messages in either byte order.
mod erased {
    pub trait Encode {
        fn le(&self) -> Vec<u8>;
        fn be(&self) -> Vec<u8>;
    }
    impl<T: serde::Serialize> Encode for T {
        fn le(&self) -> Vec<u8> {
            trajdrift::decode::cdr::encode_le(self)
        }
        fn be(&self) -> Vec<u8> {
            trajdrift::decode::cdr::encode_be(self)
        }
    }
}

#[test]
fn every_layout_reads_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let n = 200;
    let mut results = Vec::new();
    for layout in [
        Layout::ChunkedZstd,
        Layout::ChunkedLz4,
        Layout::ChunkedUncompressed,
        Layout::Unchunked,
        Layout::NoSummary,
    ] {
        for big_endian in [false, true] {
            let path = dir.path().join(format!("{layout:?}_{big_endian}.mcap"));
            write_mcap(&path, layout, n, big_endian);
            let source = McapSource::open(&path).unwrap();
            let ex = source
                .extract(
                    &topics(&["/pose", "/point", "/fix", "/pose"]),
                    &Default::default(),
                    &|_| {},
                )
                .unwrap();
            assert!(ex.warnings.is_empty(), "{layout:?}: {:?}", ex.warnings);
            let [p, q, f, again] = &ex.topics[..] else {
                panic!("four topics")
            };
            assert_eq!(p.trajectory.len(), n as usize, "{layout:?}");
            assert_eq!(p.trajectory, again.trajectory);
            assert_eq!(p.trajectory.positions, q.trajectory.positions);
            assert_eq!(p.trajectory.stamps_ns[1], pose(1).header.stamp.to_ns());
            assert_eq!(p.trajectory.positions[7].x, 7.0 * 0.1);
            assert_eq!((f.messages, f.invalid_dropped), (n as u64, 2));
            assert_eq!(f.trajectory.len(), n as usize - 2);
            // Default origin = the first valid fix.
            assert_eq!(f.geodetic_origin, Some([46.78, -71.27, 50.0]));
            let listed = source.topics().unwrap();
            assert_eq!(listed.len(), 5);
            assert!(
                listed.iter().all(|t| t.message_count == n as u64),
                "{listed:?}"
            );
            let readable: Vec<bool> = listed.iter().map(|t| t.readable).collect();
            assert_eq!(readable, [true, true, true, false, false]);
            // The JSON-encoded channel has a supported schema but cannot be decoded.
            let err = source
                .extract(&topics(&["/json_pose"]), &Default::default(), &|_| {})
                .unwrap_err();
            assert!(
                matches!(&err, Error::UnsupportedType { type_name, .. } if type_name.contains("json")),
                "{err}"
            );
            results.push(ex);
        }
    }
    for r in &results[1..] {
        for (a, b) in r.topics.iter().zip(&results[0].topics) {
            assert_eq!(a.trajectory, b.trajectory);
        }
    }
}

#[test]
fn nonzero_padding_and_big_endian_in_a_recording() {
    // frame_id "odom" (5 bytes with NUL) leaves 3 padding bytes before the doubles: fill them.
    let mut m = pose(1);
    m.header.frame_id = "odom".into();
    let mut le = cdr::encode_le(&m);
    let pad = 4 + 8 + 4 + 5;
    le[pad..pad + 3].copy_from_slice(&[0xFF, 0x7F, 0x01]);
    let be = cdr::encode_be(&m);
    assert_eq!(&be[..2], &[0, 0]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pad.mcap");
    {
        let file = std::fs::File::create(&path).unwrap();
        let mut w = mcap::WriteOptions::new().create(file).unwrap();
        let ty = "geometry_msgs/msg/PoseStamped";
        let s = w
            .add_schema(
                ty,
                "ros2msg",
                ros2_schemas::schema_text(ty).unwrap().as_bytes(),
            )
            .unwrap();
        let ch = w.add_channel(s, "/p", "cdr", &BTreeMap::new()).unwrap();
        for (i, data) in [le, be].iter().enumerate() {
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: i as u32,
                    log_time: i as u64,
                    publish_time: i as u64,
                },
                data,
            )
            .unwrap();
        }
        w.finish().unwrap();
    }
    let ex = extract(&path, &["/p"], &ExtractOptions::default());
    let t = &ex.topics[0];
    // Both messages decode to the same sample; the second is a duplicate stamp.
    assert_eq!(
        (t.messages, t.duplicate_stamps, t.trajectory.len()),
        (2, 1, 1)
    );
    assert_eq!(t.trajectory.positions[0].x, m.pose.position.x);
}

#[test]
fn decode_error_names_topic_and_message() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcap");
    {
        let file = std::fs::File::create(&path).unwrap();
        let mut w = mcap::WriteOptions::new().create(file).unwrap();
        let ty = "nav_msgs/msg/Odometry";
        let s = w
            .add_schema(
                ty,
                "ros2msg",
                ros2_schemas::schema_text(ty).unwrap().as_bytes(),
            )
            .unwrap();
        let ch = w.add_channel(s, "/odom", "cdr", &BTreeMap::new()).unwrap();
        // A PoseStamped on an Odometry channel: too short.
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: ch,
                sequence: 0,
                log_time: 0,
                publish_time: 0,
            },
            &cdr::encode_le(&pose(0)),
        )
        .unwrap();
        w.finish().unwrap();
    }
    let err = McapSource::open(&path)
        .unwrap()
        .extract(&topics(&["/odom"]), &Default::default(), &|_| {})
        .unwrap_err();
    assert!(
        matches!(&err, Error::Decode { topic, index: 0, .. } if topic == "/odom"),
        "{err}"
    );
}

//! `eval --annotate`: the annotated recording, read back with the mcap crate, keeps every input record
//! (same ids, bytes and times, attachments and metadata) and adds the trajdrift channels with the right
//! counts, the aligned stamps shifted by exactly Δt_ns = round(Δt × 10⁹).

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use mcap::records::Record;

/// Offset given on the command line: not a whole number of nanoseconds, to check the rounding.
const DT: &str = "0.1234567894";
const DT_NS: i64 = 123_456_789;

#[derive(Debug, Default)]
struct Contents {
    /// channel id → (topic, schema id, encoding)
    channels: BTreeMap<u16, (String, u16, String)>,
    schemas: BTreeMap<u16, (String, String, Vec<u8>)>,
    /// (channel id, sequence, log time, publish time, data), file order.
    messages: Vec<(u16, u32, u64, u64, Vec<u8>)>,
    attachments: Vec<(String, String, u64, Vec<u8>)>,
    metadata: Vec<(String, BTreeMap<String, String>)>,
}

fn read(path: &Path) -> Contents {
    let buf = std::fs::read(path).unwrap();
    let mut c = Contents::default();
    for r in mcap::read::ChunkFlattener::new(&buf).unwrap() {
        match r.unwrap() {
            Record::Schema { header, data } => {
                c.schemas
                    .insert(header.id, (header.name, header.encoding, data.into_owned()));
            }
            Record::Channel(ch) => {
                c.channels
                    .insert(ch.id, (ch.topic, ch.schema_id, ch.message_encoding));
            }
            Record::Message { header, data } => c.messages.push((
                header.channel_id,
                header.sequence,
                header.log_time,
                header.publish_time,
                data.into_owned(),
            )),
            Record::Attachment { header, data, .. } => c.attachments.push((
                header.name,
                header.media_type,
                header.log_time,
                data.into_owned(),
            )),
            Record::Metadata(m) => c.metadata.push((m.name, m.metadata)),
            _ => {}
        }
    }
    c
}

fn compression(path: &Path) -> String {
    let buf = std::fs::read(path).unwrap();
    let s = mcap::Summary::read(&buf).unwrap().unwrap();
    s.chunk_indexes[0].compression.clone()
}

fn annotate(rec: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let json = out.with_extension("json");
    let o = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .arg("eval")
        .arg(rec)
        .args([
            "--reference",
            "/reference/position",
            "--estimate",
            "/estimate/odom",
            "--time-offset",
            DT,
            "--window",
            "5,10",
            "--quiet",
            "--annotate",
        ])
        .arg(out)
        .arg("--json")
        .arg(&json)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        o.status.code() == Some(0) || o.status.code() == Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap()
}

fn stamp_ns(data: &[u8]) -> i64 {
    let sec = i32::from_le_bytes(data[4..8].try_into().unwrap()) as i64;
    let ns = u32::from_le_bytes(data[8..12].try_into().unwrap()) as i64;
    sec * 1_000_000_000 + ns
}

/// Checks `out` against `input` and the report; returns the new topics' counts.
fn check(input: &Path, out: &Path, report: &serde_json::Value) -> BTreeMap<String, usize> {
    let a = read(input);
    let b = read(out);
    // Every input schema, channel and message, same ids, bytes and times.
    for (id, s) in &a.schemas {
        assert_eq!(b.schemas.get(id), Some(s), "schema {id}");
    }
    for (id, ch) in &a.channels {
        assert_eq!(b.channels.get(id), Some(ch), "channel {id}");
    }
    let new: BTreeMap<u16, &str> = b
        .channels
        .iter()
        .filter(|(id, _)| !a.channels.contains_key(id))
        .map(|(id, (t, _, _))| (*id, t.as_str()))
        .collect();
    assert!(
        new.values().all(|t| t.starts_with("/trajdrift/")),
        "{new:?}"
    );
    let copied: Vec<_> = b
        .messages
        .iter()
        .filter(|m| !new.contains_key(&m.0))
        .collect();
    assert_eq!(copied.len(), a.messages.len());
    let mut sorted_a: Vec<_> = a.messages.iter().collect();
    let mut sorted_b = copied.clone();
    sorted_a.sort();
    sorted_b.sort();
    assert!(sorted_a == sorted_b, "copied messages differ");
    for att in &a.attachments {
        assert!(b.attachments.contains(att), "attachment {}", att.0);
    }
    for m in &a.metadata {
        assert!(b.metadata.contains(m), "metadata {}", m.0);
    }
    // The new channels.
    let mut counts = BTreeMap::new();
    for m in &b.messages {
        if let Some(t) = new.get(&m.0) {
            *counts.entry(t.to_string()).or_insert(0usize) += 1;
        }
    }
    let est_id = *a
        .channels
        .iter()
        .find(|(_, c)| c.0 == "/estimate/odom")
        .unwrap()
        .0;
    let aligned_id = *new
        .iter()
        .find(|(_, t)| **t == "/trajdrift/estimate/odom/aligned")
        .unwrap()
        .0;
    assert_eq!(
        b.channels[&aligned_id].1, a.channels[&est_id].1,
        "same schema"
    );
    let inputs: Vec<_> = a.messages.iter().filter(|m| m.0 == est_id).collect();
    let aligned: Vec<_> = b.messages.iter().filter(|m| m.0 == aligned_id).collect();
    assert_eq!(inputs.len(), aligned.len());
    for (i, o) in inputs.iter().zip(&aligned) {
        assert_eq!(o.2 as i64, i.2 as i64 + DT_NS, "log time");
        assert_eq!(stamp_ns(&o.4), stamp_ns(&i.4) + DT_NS, "header stamp");
        assert_eq!(o.4[12..], i.4[12..], "rest of the message");
        assert_eq!(o.4[..4], i.4[..4]);
    }
    let windows: usize = report["estimates"][0]["drift_error"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["per_window"].as_array().unwrap().len())
        .sum();
    assert_eq!(counts["/trajdrift/estimate/odom/drift_error"], windows);
    assert!(counts["/trajdrift/estimate/odom/curvature"] > 0);
    assert!(counts["/trajdrift/reference/curvature"] > 0);
    // Metadata and attachment.
    let meta = &b.metadata.iter().find(|m| m.0 == "trajdrift").unwrap().1;
    assert_eq!(meta["tool.version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(meta["estimate/odom.time_offset.applied_s"], DT);
    assert_eq!(meta["parameters.windows_m"], "[5.0,10.0]");
    let att = b
        .attachments
        .iter()
        .find(|x| x.0 == "trajdrift-report.json")
        .unwrap();
    let embedded: serde_json::Value = serde_json::from_slice(&att.3).unwrap();
    assert_eq!(&embedded, report);
    counts
}

#[test]
fn annotated_fixtures_keep_every_record_and_add_the_results() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for m in common::MISSIONS {
        let input = common::mission(&shared, m).join("mission.mcap");
        let out = dir.path().join(format!("{m}.mcap"));
        let report = annotate(&input, &out, &[]);
        let counts = check(&input, &out, &report);
        assert_eq!(compression(&out), compression(&input), "{m}");
        // `trajdrift topics` lists the new channels with their counts.
        let topics = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
            .arg("topics")
            .arg(&out)
            .args(["--json", "-"])
            .output()
            .unwrap();
        let topics: serde_json::Value = serde_json::from_slice(&topics.stdout).unwrap();
        for (t, n) in &counts {
            let listed = topics["topics"]
                .as_array()
                .unwrap()
                .iter()
                .find(|x| x["topic"] == t.as_str())
                .unwrap_or_else(|| panic!("{m}: topics does not list {t}"));
            assert_eq!(listed["message_count"].as_u64(), Some(*n as u64), "{m} {t}");
        }
        assert_eq!(
            counts["/trajdrift/estimate/odom/aligned"],
            report["estimates"][0]["samples"].as_u64().unwrap() as usize
                + report["estimates"][0]["dropped_samples"].as_u64().unwrap() as usize,
            "{m}"
        );
    }
}

/// A recording with an attachment, a metadata record and lz4 chunks, from a fixture.
fn with_extras(input: &Path, out: &Path) {
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .compression(Some(mcap::Compression::Lz4))
        .create(std::io::BufWriter::new(std::fs::File::create(out).unwrap()))
        .unwrap();
    copy_into(input, &mut w, |_, _| {});
    w.attach(&mcap::Attachment {
        log_time: 5,
        create_time: 6,
        name: "calibration.yaml".into(),
        media_type: "text/yaml".into(),
        data: b"lever: [0, 0.3, 0]\n".as_slice().into(),
    })
    .unwrap();
    w.write_metadata(&mcap::records::Metadata {
        name: "robot".into(),
        metadata: BTreeMap::from([("name".to_string(), "anymal".to_string())]),
    })
    .unwrap();
    w.finish().unwrap();
}

#[test]
fn attachments_metadata_and_lz4_survive_and_tum_estimates_become_poses() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let fixture = common::mission(&shared, "lever_arm");
    let input: PathBuf = dir.path().join("extras.mcap");
    with_extras(&fixture.join("mission.mcap"), &input);
    let out = dir.path().join("out.mcap");
    let tum = fixture.join("estimate.tum");
    let tum_arg = format!("tum={}", tum.display());
    let report = annotate(&input, &out, &["--estimate-file", &tum_arg]);
    let counts = check(&input, &out, &report);
    assert_eq!(compression(&out), "lz4");
    let tum_samples = report["estimates"][1]["samples"].as_u64().unwrap() as usize;
    assert_eq!(counts["/trajdrift/tum/aligned"], tum_samples);
    let b = read(&out);
    let (_, (_, schema, enc)) = b
        .channels
        .iter()
        .find(|(_, c)| c.0 == "/trajdrift/tum/aligned")
        .unwrap();
    assert_eq!(enc, "cdr");
    assert_eq!(b.schemas[schema].0, "geometry_msgs/msg/PoseStamped");

    // An existing output is refused without --force, the input itself always.
    let again = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .arg("eval")
        .arg(&input)
        .args([
            "--reference",
            "/reference/position",
            "--estimate",
            "/estimate/odom",
            "--annotate",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    let same = Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .arg("eval")
        .arg(&input)
        .args([
            "--reference",
            "/reference/position",
            "--estimate",
            "/estimate/odom",
            "--force",
            "--annotate",
        ])
        .arg(&input)
        .output()
        .unwrap();
    assert_eq!(same.status.code(), Some(2));
}

/// Under a linear or piecewise clock model the aligned channel follows the model stamp by stamp: every
/// aligned message moved (stamp, log and publish time) by one shift, the shifts not all equal, and
/// every stamp `--export-aligned` wrote (what Drift Error saw) present on the channel: the header
/// stamps, or with `--stamp log` the log times.
#[test]
fn aligned_channel_follows_a_non_constant_clock_model() {
    let Some(shared) = common::shared() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for (m, model) in [("clock_drift", "linear"), ("clock_step", "piecewise")] {
        let input = common::mission(&shared, m).join("mission.mcap");
        follows_the_model(&input, &dir.path().join(m), model, false);
    }
    // The estimate's log times 3 s after its header stamps: with `--stamp log` the model is a function
    // of the log time, and a message near the step takes the segment of its log time.
    let late = dir.path().join("late.mcap");
    with_late_log_times(
        &common::mission(&shared, "clock_step").join("mission.mcap"),
        &late,
        "/estimate/odom",
        3_000_000_000,
    );
    follows_the_model(&late, &dir.path().join("late-annotated"), "piecewise", true);
}

/// Evaluates `input` with `--annotate` and `--export-aligned` into files beside `stem` and checks the
/// aligned channel against the model and the export (see the test above).
fn follows_the_model(input: &Path, stem: &Path, model: &str, log_stamps: bool) {
    let (out, tum, json) = (
        stem.with_extension("mcap"),
        stem.with_extension("tum"),
        stem.with_extension("json"),
    );
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_trajdrift"));
    cmd.arg("eval")
        .arg(input)
        .args(["--reference", "/reference/position"])
        .args(["--estimate", "/estimate/odom", "--quiet", "--annotate"])
        .arg(&out)
        .arg("--export-aligned")
        .arg(&tum)
        .arg("--json")
        .arg(&json);
    if log_stamps {
        cmd.args(["--stamp", "log"]);
    }
    let o = cmd.output().unwrap();
    let m = input.display();
    assert!(matches!(o.status.code(), Some(0 | 3)), "{m}: {o:?}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(report["estimates"][0]["time_offset"]["model"], model, "{m}");

    let (a, b) = (read(input), read(&out));
    let channel = |c: &Contents, topic: &str| {
        c.channels
            .iter()
            .find(|(_, v)| v.0 == topic)
            .map(|(id, _)| *id)
            .unwrap()
    };
    let (src, dst) = (
        channel(&a, "/estimate/odom"),
        channel(&b, "/trajdrift/estimate/odom/aligned"),
    );
    // Input messages by their bytes after the stamp (unique: the pose differs sample to sample).
    let originals: BTreeMap<&[u8], (i64, u64, u64)> = a
        .messages
        .iter()
        .filter(|x| x.0 == src)
        .map(|x| (&x.4[12..], (stamp_ns(&x.4), x.2, x.3)))
        .collect();
    let mut shifts = std::collections::BTreeSet::new();
    let mut stamps = std::collections::BTreeSet::new();
    for x in b.messages.iter().filter(|x| x.0 == dst) {
        let (stamp, log, publish) = originals[&x.4[12..]];
        let dt = stamp_ns(&x.4) - stamp;
        assert_eq!(x.2 as i64 - log as i64, dt, "{m}: log time");
        assert_eq!(x.3 as i64 - publish as i64, dt, "{m}: publish time");
        shifts.insert(dt);
        stamps.insert(if log_stamps {
            x.2 as i64
        } else {
            stamp_ns(&x.4)
        });
    }
    assert!(shifts.len() > 1, "{m}: one shift for every message");
    let exported = std::fs::read_to_string(&tum).unwrap();
    for line in exported.lines().filter(|l| !l.starts_with('#')) {
        let t = line.split_whitespace().next().unwrap();
        let (s, ns) = t.split_once('.').unwrap();
        let stamp = s.parse::<i64>().unwrap() * 1_000_000_000 + ns.parse::<i64>().unwrap();
        assert!(
            stamps.contains(&stamp),
            "{m}: exported stamp {t} not on the aligned channel"
        );
    }
}

/// A copy of `input` whose messages on `topic` are logged (and published) `dt_ns` later.
fn with_late_log_times(input: &Path, out: &Path, topic: &str, dt_ns: u64) {
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .create(std::io::BufWriter::new(std::fs::File::create(out).unwrap()))
        .unwrap();
    copy_into(input, &mut w, |t, header| {
        if t == topic {
            header.log_time += dt_ns;
            header.publish_time += dt_ns;
        }
    });
    w.finish().unwrap();
}

/// Copies the schemas, channels and messages of `input` into `w` (same ids), each message header
/// passed through `edit` with its channel's topic.
fn copy_into<W: std::io::Write + std::io::Seek>(
    input: &Path,
    w: &mut mcap::Writer<W>,
    mut edit: impl FnMut(&str, &mut mcap::records::MessageHeader),
) {
    let buf = std::fs::read(input).unwrap();
    let mut topics = BTreeMap::new();
    for r in mcap::read::ChunkFlattener::new(&buf).unwrap() {
        match r.unwrap() {
            Record::Schema { header, data } => {
                w.add_schema_with_id(header.id, &header.name, &header.encoding, &data)
                    .unwrap();
            }
            Record::Channel(c) => {
                w.add_channel_with_id(
                    c.id,
                    c.schema_id,
                    &c.topic,
                    &c.message_encoding,
                    &c.metadata,
                )
                .unwrap();
                topics.insert(c.id, c.topic);
            }
            Record::Message { mut header, data } => {
                edit(&topics[&header.channel_id], &mut header);
                w.write_to_known_channel(&header, &data).unwrap();
            }
            _ => {}
        }
    }
}

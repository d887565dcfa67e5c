//! The MCAP conformance suite (foxglove/mcap tests/conformance, 416 variants): whatever the layout
//! (chunked or not, indexes, statistics, summary offsets, repeated schemas/channels, padding), the
//! reading path the product uses finds every channel and every message, in file order.

use crate::common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use serde_json::Value;
use trajdrift::sources::mcap::{for_each_message, McapSource};
use trajdrift::sources::Source;

/// A record's fields as a map (the JSON lists them as `[name, value]` pairs).
fn fields(record: &Value) -> BTreeMap<String, Value> {
    record["fields"]
        .as_array()
        .expect("fields")
        .iter()
        .map(|f| (f[0].as_str().expect("field name").to_string(), f[1].clone()))
        .collect()
}

fn num(v: &Value) -> u64 {
    v.as_str()
        .expect("number as string")
        .parse()
        .expect("number")
}

/// (channel id, sequence, log time, publish time, data) of one message.
type Msg = (u16, u32, u64, u64, Vec<u8>);

#[test]
fn every_variant_reads_every_channel_and_message() {
    let Some(shared) = common::shared() else {
        return;
    };
    let root = shared.join("conformance/data");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("conformance/data")
        .flat_map(|d| std::fs::read_dir(d.expect("entry").path()).expect("variant folder"))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "mcap"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 416, "conformance variants");

    let mut messages_checked = 0;
    for path in &files {
        let expected: Value =
            serde_json::from_str(&std::fs::read_to_string(path.with_extension("json")).unwrap())
                .unwrap();
        let mut schema_names: BTreeMap<u64, String> = BTreeMap::new();
        let mut channels: BTreeSet<(u16, String, String, String)> = BTreeSet::new();
        let mut messages: Vec<Msg> = Vec::new();
        let mut in_summary = false;
        for record in expected["records"].as_array().expect("records") {
            let f = fields(record);
            match record["type"].as_str().expect("type") {
                "Schema" => {
                    schema_names.insert(num(&f["id"]), f["name"].as_str().unwrap().into());
                }
                "Channel" => {
                    let schema = schema_names
                        .get(&num(&f["schema_id"]))
                        .cloned()
                        .unwrap_or_default();
                    channels.insert((
                        num(&f["id"]) as u16,
                        f["topic"].as_str().unwrap().into(),
                        schema,
                        f["message_encoding"].as_str().unwrap().into(),
                    ));
                }
                "Message" if !in_summary => messages.push((
                    num(&f["channel_id"]) as u16,
                    num(&f["sequence"]) as u32,
                    num(&f["log_time"]),
                    num(&f["publish_time"]),
                    f["data"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|b| num(b) as u8)
                        .collect(),
                )),
                "DataEnd" => in_summary = true,
                _ => {}
            }
        }

        // The streaming pass `extract` is built on, selecting every channel.
        let mut got: Vec<Msg> = Vec::new();
        let outcome = for_each_message(
            path,
            |_| true,
            &|_| {},
            |c, m| {
                assert_eq!(c.id, m.channel_id);
                got.push((
                    m.channel_id,
                    m.sequence,
                    m.log_time,
                    m.publish_time,
                    m.data.to_vec(),
                ));
                Ok(())
            },
        )
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let name = path.display();
        assert_eq!(outcome.truncated_at, None, "{name}");
        assert_eq!(got, messages, "{name}: messages");
        let found: BTreeSet<(u16, String, String, String)> = outcome
            .channels
            .iter()
            .map(|c| {
                (
                    c.id,
                    c.topic.clone(),
                    c.schema_name.clone(),
                    c.message_encoding.clone(),
                )
            })
            .collect();
        assert_eq!(found, channels, "{name}: channels");

        // `topics` (summary statistics when present, else a pass) counts the same messages.
        let topics = McapSource::open(path).unwrap().topics().unwrap();
        assert_eq!(topics.len(), channels.len(), "{name}: topics");
        for (id, topic, schema, _) in &channels {
            let info = topics
                .iter()
                .find(|t| &t.topic == topic)
                .unwrap_or_else(|| panic!("{name}: topic {topic} not listed"));
            assert_eq!(&info.type_name, schema);
            let count = messages.iter().filter(|m| m.0 == *id).count() as u64;
            assert_eq!(info.message_count, count, "{name}: count of {topic}");
            assert!(!info.readable, "{name}: test schemas are not trajectories");
        }
        messages_checked += messages.len();
    }
    assert!(
        messages_checked > 1000,
        "{messages_checked} messages checked"
    );
}

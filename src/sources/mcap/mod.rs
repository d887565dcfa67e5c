//! MCAP recordings (ROS 2: `cdr` messages with `ros2msg` schemas) as a [`Source`].
//!
//! [`stream`] is the single streaming pass everything is built on, [`summary`] the optional index at
//! the end of the file; this file turns selected channels into trajectories.

pub mod stream;
pub mod summary;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use crate::decode::{self, geodesy, MessageKind, SamplePosition};
use crate::error::{Error, Result};
use crate::sources::{
    ExtractOptions, ExtractedTopic, Extraction, Progress, Source, StampSource, TopicInfo, Warning,
};
use crate::trajectory::Trajectory;

pub use stream::{for_each_message, ChannelInfo, MessageRef, StreamOutcome};
pub use summary::{read_summary, SummaryInfo};

/// The only message encoding trajdrift decodes.
const CDR: &str = "cdr";

/// An MCAP file on disk. Opening checks the magic; nothing else is read until asked.
#[derive(Debug, Clone)]
pub struct McapSource {
    path: PathBuf,
    size: u64,
}

impl McapSource {
    /// Opens `path`: [`Error::Io`] when it cannot be read, [`Error::NotMcap`] when it does not start
    /// with the MCAP magic.
    pub fn open(path: &Path) -> Result<McapSource> {
        let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let size = file.metadata().map_err(|e| Error::io(path, e))?.len();
        stream::read_magic(&mut file, path)?;
        Ok(McapSource {
            path: path.to_path_buf(),
            size,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn unsupported(&self, c: &ChannelInfo) -> Error {
        let bad_encoding = decode::message_kind(&c.schema_name).is_some();
        Error::UnsupportedType {
            path: self.path.clone(),
            topic: c.topic.clone(),
            type_name: if bad_encoding {
                format!(
                    "{} with message encoding `{}`",
                    c.schema_name, c.message_encoding
                )
            } else if c.schema_name.is_empty() {
                format!("(no schema, message encoding `{}`)", c.message_encoding)
            } else {
                c.schema_name.clone()
            },
            supported: decode::supported_types()
                .iter()
                .map(|t| format!("{t} ({CDR})"))
                .collect(),
        }
    }

    /// Checks that every requested topic is among `channels` with a readable type.
    fn check_requested(&self, topics: &[String], channels: &[ChannelInfo]) -> Result<()> {
        for topic in topics {
            let on_topic: Vec<&ChannelInfo> =
                channels.iter().filter(|c| &c.topic == topic).collect();
            let Some(first) = on_topic.first() else {
                let mut available: Vec<String> = channels.iter().map(|c| c.topic.clone()).collect();
                available.sort();
                available.dedup();
                return Err(Error::TopicNotFound {
                    path: self.path.clone(),
                    topic: topic.clone(),
                    available,
                });
            };
            if let Some(bad) = on_topic.iter().find(|c| readable_kind(c).is_none()) {
                return Err(self.unsupported(bad));
            }
            if on_topic
                .iter()
                .any(|c| readable_kind(c) != readable_kind(first))
            {
                return Err(self.unsupported(first));
            }
        }
        Ok(())
    }
}

/// The kind of a channel when trajdrift can decode it (a supported schema with `cdr` messages).
pub fn readable_kind(c: &ChannelInfo) -> Option<MessageKind> {
    decode::message_kind(&c.schema_name).filter(|_| c.message_encoding == CDR)
}

/// A requested topic while the pass runs.
struct Accumulator {
    kind: MessageKind,
    /// Positions; for a geodetic topic (latitude, longitude, altitude) until the end of the pass.
    trajectory: Trajectory,
    messages: u64,
    invalid_dropped: u64,
}

impl Accumulator {
    fn new(kind: MessageKind) -> Self {
        Accumulator {
            kind,
            trajectory: Trajectory::new(kind.has_orientation()),
            messages: 0,
            invalid_dropped: 0,
        }
    }
}

impl Source for McapSource {
    fn size_bytes(&self) -> u64 {
        self.size
    }

    fn topics(&self) -> Result<Vec<TopicInfo>> {
        let summary = read_summary(&self.path);
        let (channels, counts) = match summary {
            Some(SummaryInfo {
                channels,
                message_counts: Some(counts),
            }) => (channels, counts),
            _ => {
                let outcome = for_each_message(&self.path, |_| false, &|_| {}, |_, _| Ok(()))?;
                (outcome.channels, outcome.message_counts)
            }
        };
        Ok(channels
            .into_iter()
            .map(|c| TopicInfo {
                readable: readable_kind(&c).is_some(),
                message_count: counts.get(&c.id).copied().unwrap_or(0),
                topic: c.topic,
                type_name: c.schema_name,
                message_encoding: c.message_encoding,
            })
            .collect())
    }

    fn extract(
        &self,
        topics: &[String],
        options: &ExtractOptions,
        progress: Progress<'_>,
    ) -> Result<Extraction> {
        if topics.is_empty() {
            return Ok(Extraction::default());
        }
        // Fail fast on a wrong topic when the summary lists the channels.
        if let Some(summary) = read_summary(&self.path) {
            self.check_requested(topics, &summary.channels)?;
        }

        // Each distinct requested topic once; `unique[i]` gets accumulator `i`.
        let mut unique: Vec<&str> = Vec::new();
        for t in topics {
            if !unique.contains(&t.as_str()) {
                unique.push(t.as_str());
            }
        }
        let mut accumulators: Vec<Option<Accumulator>> = unique.iter().map(|_| None).collect();
        // Channel id → accumulator index, `None` for a channel whose type differs from the topic's first.
        let mut route: HashMap<u16, Option<usize>> = HashMap::new();

        let outcome = for_each_message(
            &self.path,
            |c| unique.contains(&c.topic.as_str()) && readable_kind(c).is_some(),
            progress,
            |c, m| {
                let slot = *route.entry(c.id).or_insert_with(|| {
                    let i = unique.iter().position(|t| *t == c.topic)?;
                    let kind = readable_kind(c)?;
                    let acc = accumulators[i].get_or_insert_with(|| Accumulator::new(kind));
                    // Two channels of one topic with different types: reported after the pass.
                    (acc.kind == kind).then_some(i)
                });
                let Some(acc) = slot.and_then(|i| accumulators[i].as_mut()) else {
                    return Ok(());
                };
                let index = acc.messages;
                acc.messages += 1;
                let sample =
                    decode::decode_sample(acc.kind, m.data).map_err(|detail| Error::Decode {
                        path: self.path.clone(),
                        topic: c.topic.clone(),
                        index,
                        detail,
                    })?;
                if !sample.is_valid() {
                    acc.invalid_dropped += 1;
                    return Ok(());
                }
                let stamp_ns = match options.stamp {
                    StampSource::Header => sample.stamp_ns,
                    StampSource::Log => i64::try_from(m.log_time).unwrap_or(i64::MAX),
                };
                let position = match sample.position {
                    SamplePosition::Local(p) => p,
                    SamplePosition::Geodetic {
                        lat_deg,
                        lon_deg,
                        alt_m,
                        ..
                    } => Vector3::new(lat_deg, lon_deg, alt_m),
                };
                acc.trajectory.push(stamp_ns, position, sample.orientation);
                Ok(())
            },
        )?;
        self.check_requested(topics, &outcome.channels)?;

        let mut warnings = Vec::new();
        if let Some(offset) = outcome.truncated_at {
            warnings.push(Warning {
                code: "truncated_recording".into(),
                message: format!(
                    "{}: recording cut short at byte {offset} (no footer; the recorder probably stopped abruptly); read up to the last complete record",
                    self.path.display()
                ),
            });
        }

        // Topics without a message still get their (empty) trajectory of the right kind.
        let mut accumulators: Vec<Accumulator> = accumulators
            .into_iter()
            .zip(&unique)
            .map(|(acc, topic)| {
                acc.or_else(|| {
                    outcome
                        .channels
                        .iter()
                        .filter(|c| c.topic == *topic)
                        .find_map(readable_kind)
                        .map(Accumulator::new)
                })
                .ok_or_else(|| Error::InvalidArgument(format!("{topic}: no readable channel")))
            })
            .collect::<Result<_>>()?;
        let duplicates: Vec<u64> = accumulators
            .iter_mut()
            .map(|a| a.trajectory.sort_dedup() as u64)
            .collect();

        // The ENU origin: given, or the first valid fix (by stamp) of the first geodetic topic
        // requested that has one.
        let origin = options.origin.or_else(|| {
            accumulators
                .iter()
                .filter(|a| a.kind.is_geodetic())
                .find_map(|a| a.trajectory.positions.first())
                .map(|p| [p.x, p.y, p.z])
        });

        let mut done: Vec<Option<ExtractedTopic>> = accumulators
            .into_iter()
            .zip(duplicates)
            .zip(&unique)
            .map(|((mut acc, duplicate_stamps), topic)| {
                let mut geodetic_origin = None;
                if acc.kind.is_geodetic() {
                    // `origin` is Some whenever a geodetic topic has a sample.
                    if let Some(o) = origin {
                        for p in &mut acc.trajectory.positions {
                            *p = geodesy::geodetic_to_enu(p.x, p.y, p.z, o);
                        }
                        geodetic_origin = Some(o);
                    }
                }
                Some(ExtractedTopic {
                    topic: topic.to_string(),
                    type_name: acc.kind.type_name().to_string(),
                    trajectory: acc.trajectory,
                    messages: acc.messages,
                    invalid_dropped: acc.invalid_dropped,
                    duplicate_stamps,
                    geodetic_origin,
                })
            })
            .collect();
        // In request order; a topic requested twice is cloned.
        let mut topics_out = Vec::with_capacity(topics.len());
        for t in topics {
            let i = unique.iter().position(|u| u == t).unwrap_or(0);
            let first = done[i].take();
            let next = match first {
                Some(x) => x,
                None => match topics_out.iter().find(|x: &&ExtractedTopic| &x.topic == t) {
                    Some(x) => x.clone(),
                    None => continue,
                },
            };
            topics_out.push(next);
        }
        Ok(Extraction {
            topics: topics_out,
            warnings,
        })
    }
}

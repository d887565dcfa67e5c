//! Turning one streaming pass over any recording into trajectories.
//!
//! MCAP files, ROS 1 bags and rosbag2 folders differ in how they store messages, not in what
//! extraction does with them: each implements [`Recording`] (its channels, one pass over its
//! messages) and [`extract`] does the rest (routing by topic, decoding by schema and message
//! encoding, dropping invalid samples, sorting, the ENU origin of geodetic topics).

use std::collections::HashMap;
use std::path::Path;

use nalgebra::Vector3;

use crate::decode::{self, geodesy, Encoding, MessageKind, SamplePosition};
use crate::error::{Error, Result};
use crate::sources::recording::{ChannelInfo, Recording, StreamOutcome};
use crate::sources::tf_chain::{self, ChainRequest, TfCollector};
use crate::sources::Warning;
use crate::sources::{
    ExtractOptions, ExtractedTopic, Extraction, Progress, Source, StampSource, StaticTransform,
    TopicInfo,
};
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// Every recording is a [`Source`]: its topics from its channel counts, its trajectories by
/// `extract`, its TF frames by [`crate::sources::tf_frames::frame_pairs`].
impl<R: Recording> Source for R {
    fn size_bytes(&self) -> u64 {
        self.recording_size()
    }

    fn topics(&self) -> Result<Vec<TopicInfo>> {
        let (channels, counts) = self.channel_counts()?;
        Ok(topic_infos(channels, &counts))
    }

    fn indexed_type(&self, topic: &str) -> Option<String> {
        self.known_channels()?
            .into_iter()
            .find(|c| c.topic == topic)
            .map(|c| c.schema_name)
    }

    fn extract(
        &self,
        topics: &[String],
        options: &ExtractOptions,
        progress: Progress<'_>,
    ) -> Result<Extraction> {
        extract(self, topics, options, progress)
    }

    fn frame_pairs(
        &self,
        progress: Progress<'_>,
    ) -> Result<Vec<crate::sources::tf_frames::FramePair>> {
        crate::sources::tf_frames::frame_pairs(self, progress)
    }

    fn frame_pairs_checked(
        &self,
        progress: Progress<'_>,
    ) -> Result<(Vec<crate::sources::tf_frames::FramePair>, Vec<Warning>)> {
        let (pairs, truncated_at) = crate::sources::tf_frames::scan(self, progress)?;
        let warnings = truncated_at.map(|o| self.truncation_warning(o));
        Ok((pairs, warnings.into_iter().collect()))
    }
}

/// The kind and encoding of a channel when trajdrift can decode it.
pub fn channel_kind(c: &ChannelInfo) -> Option<(MessageKind, Encoding)> {
    Some((
        decode::message_kind(&c.schema_name)?,
        Encoding::from_name(&c.message_encoding)?,
    ))
}

/// Every supported type with the encodings it is read in, for error messages.
pub fn supported_list() -> Vec<String> {
    decode::supported_types()
        .iter()
        .map(|t| format!("{t} (cdr, ros1)"))
        .collect()
}

/// `TopicInfo` rows from channels and counts.
pub fn topic_infos(channels: Vec<ChannelInfo>, counts: &HashMap<u16, u64>) -> Vec<TopicInfo> {
    channels
        .into_iter()
        .map(|c| TopicInfo {
            readable: channel_kind(&c).is_some(),
            message_count: counts.get(&c.id).copied().unwrap_or(0),
            topic: c.topic,
            type_name: c.schema_name,
            message_encoding: c.message_encoding,
            frame_pairs: Vec::new(),
            tf_chains: Vec::new(),
        })
        .collect()
}

fn unsupported(path: &Path, c: &ChannelInfo) -> Error {
    let bad_encoding = decode::message_kind(&c.schema_name).is_some();
    Error::UnsupportedType {
        path: path.to_path_buf(),
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
        supported: supported_list(),
    }
}

/// Checks that every requested topic is among `channels` with a readable type.
pub fn check_requested(path: &Path, topics: &[String], channels: &[ChannelInfo]) -> Result<()> {
    for topic in topics {
        let on_topic: Vec<&ChannelInfo> = channels.iter().filter(|c| &c.topic == topic).collect();
        let Some(first) = on_topic.first() else {
            let mut available: Vec<String> = channels.iter().map(|c| c.topic.clone()).collect();
            available.sort();
            available.dedup();
            return Err(Error::TopicNotFound {
                path: path.to_path_buf(),
                topic: topic.clone(),
                available,
            });
        };
        if let Some(bad) = on_topic.iter().find(|c| channel_kind(c).is_none()) {
            return Err(unsupported(path, bad));
        }
        let kind = |c: &ChannelInfo| channel_kind(c).map(|k| k.0);
        if on_topic.iter().any(|c| kind(c) != kind(first)) {
            return Err(unsupported(path, first));
        }
    }
    Ok(())
}

/// Checks that a recording asked for TF chains has a `/tf` or `/tf_static` channel.
fn check_tf_channels(path: &Path, chains: &[ChainRequest], channels: &[ChannelInfo]) -> Result<()> {
    let Some(first) = chains.first() else {
        return Ok(());
    };
    if channels.iter().any(tf_chain::is_tf_channel) {
        return Ok(());
    }
    let mut available: Vec<String> = channels.iter().map(|c| c.topic.clone()).collect();
    available.sort();
    available.dedup();
    Err(Error::TfChain {
        path: path.to_path_buf(),
        topic: first.topic.clone(),
        detail: format!(
            "a TF chain needs a /tf or /tf_static channel of type tf2_msgs/msg/TFMessage, and there is none (topics present: {})",
            available.join(", ")
        ),
    })
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
    /// `positions_only`: drop the orientations (see [`ExtractOptions::positions_only`]).
    fn new(kind: MessageKind, positions_only: bool) -> Self {
        Accumulator {
            kind,
            trajectory: Trajectory::new(kind.has_orientation() && !positions_only),
            messages: 0,
            invalid_dropped: 0,
        }
    }
}

/// Reads the trajectories of `topics` from `rec` in one pass (see [`crate::sources::Source::extract`]).
/// Topics named `/tf:PARENT:CHILD` are TF chains ([`tf_chain`]): their edges are collected in the
/// same pass.
pub fn extract(
    rec: &dyn Recording,
    topics: &[String],
    options: &ExtractOptions,
    progress: Progress<'_>,
) -> Result<Extraction> {
    if topics.is_empty() && options.static_lookups.is_empty() {
        return Ok(Extraction::default());
    }
    let path = rec.path();
    let requests = Requests::of(topics, options)?;
    if let Some(by_part) = side_by_side(rec, &requests, options) {
        return extract_parts(
            rec.parts(),
            (topics, &requests.unique),
            &by_part,
            options,
            progress,
        );
    }
    // Fail fast on a wrong topic when an index lists the channels.
    if let Some(channels) = rec.known_channels() {
        check_requested(path, &requests.plain, &channels)?;
        check_tf_channels(path, &requests.chains, &channels)?;
    }
    let pass = read_pass(rec, &requests, options, progress)?;
    check_requested(path, &requests.plain, &pass.outcome.channels).map_err(|e| {
        match (e, pass.outcome.truncated_at) {
            (Error::TopicNotFound { topic, .. }, Some(offset)) => Error::Damaged {
                path: path.to_path_buf(),
                offset,
                detail: format!(
                    "the recording is cut short or damaged there, and topic {topic} was not found before"
                ),
            },
            (e, _) => e,
        }
    })?;
    check_tf_channels(path, &requests.chains, &pass.outcome.channels)?;
    let tree = pass.tf.map(TfCollector::finish).unwrap_or_default();
    let static_transforms = options
        .static_lookups
        .iter()
        .map(|(from, to)| StaticTransform {
            from: from.clone(),
            to: to.clone(),
            pose: tree.static_transform(from, to),
        })
        .collect();
    let chain_topics = requests
        .chains
        .iter()
        .map(|r| chain_topic(&tree, path, r))
        .collect::<Result<Vec<_>>>()?;
    let warnings = pass
        .outcome
        .truncated_at
        .map(|offset| rec.truncation_warning(offset))
        .into_iter()
        .collect();
    let plain = finish_topics(
        pass.accumulators,
        &requests.unique,
        &pass.outcome.channels,
        options,
    )?;
    Ok(Extraction {
        topics: in_request_order(topics, &requests.unique, plain, &chain_topics),
        warnings,
        static_transforms,
    })
}

/// Which part of a multi-file recording holds each requested topic, when the parts can be extracted
/// each on its own, side by side: every part's channels are indexed, every requested topic lives in
/// exactly one part with one readable type, no TF chain or static look-up needs edges from several
/// files, and the geodetic topics (whose ENU origin is shared) are in one part or the origin is
/// given. `None` otherwise: the parts are then read one after the other in one pass, which also
/// words any error (a missing topic, a type differing between files).
fn side_by_side(
    rec: &dyn Recording,
    requests: &Requests<'_>,
    options: &ExtractOptions,
) -> Option<Vec<usize>> {
    let parts = rec.parts();
    if parts.len() < 2 || !requests.lookup_frames.is_empty() {
        return None;
    }
    let channels: Vec<Vec<ChannelInfo>> = parts
        .iter()
        .map(|p| p.known_channels())
        .collect::<Option<_>>()?;
    let mut by_part = Vec::with_capacity(requests.unique.len());
    let mut geodetic_parts: Vec<usize> = Vec::new();
    for topic in &requests.unique {
        let holding: Vec<usize> = (0..parts.len())
            .filter(|&i| channels[i].iter().any(|c| c.topic == *topic))
            .collect();
        let [part] = holding[..] else {
            return None;
        };
        let on_topic: Vec<&ChannelInfo> = channels[part]
            .iter()
            .filter(|c| c.topic == *topic)
            .collect();
        let kinds: Vec<Option<MessageKind>> = on_topic
            .iter()
            .map(|c| channel_kind(c).map(|k| k.0))
            .collect();
        let kind = kinds.first().copied().flatten()?;
        if kinds.iter().any(|k| *k != Some(kind)) {
            return None;
        }
        if kind.is_geodetic() && !geodetic_parts.contains(&part) {
            geodetic_parts.push(part);
        }
        by_part.push(part);
    }
    if geodetic_parts.len() > 1 && options.origin.is_none() {
        return None;
    }
    Some(by_part)
}

/// [`extract`] of a multi-file recording whose requested topics each live in one part (`by_part`,
/// per `unique` topic, from [`side_by_side`]): each part holding one is extracted on its own, in
/// parallel — the same trajectories as one pass over the files in turn, read in the time of the
/// largest. Memory: what each part's pass needs (one chunk at a time), plus the samples kept.
fn extract_parts(
    parts: &[Box<dyn Recording + Send + Sync>],
    (topics, unique): (&[String], &[&str]),
    by_part: &[usize],
    options: &ExtractOptions,
    progress: Progress<'_>,
) -> Result<Extraction> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU64, Ordering};
    let wanted: Vec<usize> = (0..parts.len()).filter(|i| by_part.contains(i)).collect();
    // Bytes read so far, per part; progress is their sum, never shown going back.
    let read: Vec<AtomicU64> = parts.iter().map(|_| AtomicU64::new(0)).collect();
    let shown = AtomicU64::new(0);
    let show = |n: u64| {
        if shown.fetch_max(n, Ordering::Relaxed) < n {
            progress(n);
        }
    };
    let extractions: Vec<(usize, Extraction)> = wanted
        .par_iter()
        .map(|&i| {
            let own: Vec<String> = unique
                .iter()
                .zip(by_part)
                .filter(|(_, &p)| p == i)
                .map(|(t, _)| t.to_string())
                .collect();
            let report = |n: u64| {
                read[i].store(n, Ordering::Relaxed);
                show(read.iter().map(|r| r.load(Ordering::Relaxed)).sum());
            };
            Ok((i, extract(parts[i].as_ref(), &own, options, &report)?))
        })
        .collect::<Result<_>>()?;
    // The files holding no requested topic count as read (they need not be).
    show(parts.iter().map(|p| p.recording_size()).sum());
    let mut warnings = Vec::new();
    let mut pool: Vec<Option<ExtractedTopic>> = unique.iter().map(|_| None).collect();
    for (i, e) in extractions {
        warnings.extend(e.warnings);
        for t in e.topics {
            if let Some(k) = unique
                .iter()
                .zip(by_part)
                .position(|(u, &p)| *u == t.topic && p == i)
            {
                pool[k] = Some(t);
            }
        }
    }
    let plain: Vec<ExtractedTopic> = pool.into_iter().flatten().collect();
    if plain.len() != unique.len() {
        return Err(Error::InvalidArgument(
            "internal: a topic read side by side from a mission's files went missing; please report it with the command that gave it".into(),
        ));
    }
    Ok(Extraction {
        topics: in_request_order(topics, unique, plain, &[]),
        warnings,
        static_transforms: Vec::new(),
    })
}

/// What one extraction asks for: TF chains, plain topics (each distinct one once, in `unique`), and
/// the frames the chains and the `tf-static:` lookups need.
struct Requests<'a> {
    chains: Vec<ChainRequest>,
    plain: Vec<String>,
    unique: Vec<&'a str>,
    lookup_frames: Vec<ChainRequest>,
}

impl<'a> Requests<'a> {
    fn of(topics: &'a [String], options: &ExtractOptions) -> Result<Requests<'a>> {
        let mut chains: Vec<ChainRequest> = Vec::new();
        let mut plain: Vec<String> = Vec::new();
        let mut unique: Vec<&str> = Vec::new();
        for t in topics {
            match tf_chain::parse_chain_topic(t) {
                Some(r) => {
                    let r = r?;
                    if !chains.contains(&r) {
                        chains.push(r);
                    }
                }
                None => {
                    plain.push(t.clone());
                    if !unique.contains(&t.as_str()) {
                        unique.push(t.as_str());
                    }
                }
            }
        }
        // `tf-static:` levers look up static transforms in the same pass.
        let mut lookup_frames: Vec<ChainRequest> = options
            .static_lookups
            .iter()
            .map(|(from, to)| ChainRequest {
                topic: String::new(),
                parent: tf_chain::frame_name(from).to_string(),
                child: tf_chain::frame_name(to).to_string(),
            })
            .collect();
        lookup_frames.extend(chains.iter().cloned());
        Ok(Requests {
            chains,
            plain,
            unique,
            lookup_frames,
        })
    }
}

/// What the pass over the recording collected.
struct Pass {
    /// Per distinct plain topic (`Requests::unique`), `None` when no message came.
    accumulators: Vec<Option<Accumulator>>,
    /// The `/tf` and `/tf_static` edges, when chains or lookups asked for them.
    tf: Option<TfCollector>,
    outcome: StreamOutcome,
}

/// The one streaming pass: routes each message of a requested topic to its accumulator (decoded by
/// its schema and encoding, invalid samples counted and dropped) and `/tf` edges to the collector.
fn read_pass(
    rec: &dyn Recording,
    requests: &Requests<'_>,
    options: &ExtractOptions,
    progress: Progress<'_>,
) -> Result<Pass> {
    let path = rec.path();
    let unique = &requests.unique;
    let want_tf = !requests.lookup_frames.is_empty();
    let mut tf = want_tf.then(|| TfCollector::new(&requests.lookup_frames));
    let mut tf_index: HashMap<u16, u64> = HashMap::new();
    let mut accumulators: Vec<Option<Accumulator>> = unique.iter().map(|_| None).collect();
    let positions_only = |topic: &str| options.positions_only.iter().any(|t| t == topic);
    // Channel id → (accumulator index, encoding), `None` for a channel whose type differs from the
    // topic's first.
    let mut route: HashMap<u16, Option<(usize, Encoding)>> = HashMap::new();
    let log_stamp = |log_time: u64| i64::try_from(log_time).unwrap_or(i64::MAX);

    let outcome = rec.pass(
        &mut |c| {
            (unique.contains(&c.topic.as_str()) && channel_kind(c).is_some())
                || (want_tf && tf_chain::is_tf_channel(c))
        },
        progress,
        &mut |c, m| {
            if let Some(tf) = tf.as_mut().filter(|_| tf_chain::is_tf_channel(c)) {
                let i = tf_index.entry(c.id).or_default();
                let edges = tf_chain::decode_edges(path, c, *i, m.data)?;
                *i += 1;
                let stamp = match options.stamp {
                    StampSource::Header => None,
                    StampSource::Log => Some(log_stamp(m.log_time)),
                };
                tf.push(tf_chain::is_static_channel(c), edges, stamp);
                return Ok(());
            }
            let slot = *route.entry(c.id).or_insert_with(|| {
                let i = unique.iter().position(|t| *t == c.topic)?;
                let (kind, encoding) = channel_kind(c)?;
                let acc = accumulators[i]
                    .get_or_insert_with(|| Accumulator::new(kind, positions_only(unique[i])));
                // Two channels of one topic with different types: reported after the pass.
                (acc.kind == kind).then_some((i, encoding))
            });
            let Some((acc, encoding)) =
                slot.and_then(|(i, e)| accumulators[i].as_mut().map(|a| (a, e)))
            else {
                return Ok(());
            };
            acc.take(
                path,
                &c.topic,
                encoding,
                m.data,
                options.stamp,
                log_stamp(m.log_time),
            )
        },
    )?;
    Ok(Pass {
        accumulators,
        tf,
        outcome,
    })
}

impl Accumulator {
    /// Decodes one message of the topic and keeps its sample (stamped by the header or by the
    /// log time `log_ns`); a sample the decoder marks invalid is counted and dropped. Geodetic
    /// fixes are kept as (lat, lon, alt) and projected after the pass.
    #[inline]
    fn take(
        &mut self,
        path: &Path,
        topic: &str,
        encoding: Encoding,
        data: &[u8],
        stamp: StampSource,
        log_ns: i64,
    ) -> Result<()> {
        let index = self.messages;
        self.messages += 1;
        let sample =
            decode::decode_message(self.kind, encoding, data).map_err(|detail| Error::Decode {
                path: path.to_path_buf(),
                topic: topic.to_string(),
                index,
                detail,
            })?;
        if !sample.is_valid() {
            self.invalid_dropped += 1;
            return Ok(());
        }
        let stamp_ns = match stamp {
            StampSource::Header => sample.stamp_ns,
            StampSource::Log => log_ns,
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
        self.trajectory.push(stamp_ns, position, sample.orientation);
        Ok(())
    }
}

/// The trajectory of the TF chain `r`, composed from the collected edges.
fn chain_topic(tree: &tf_chain::TfTree, path: &Path, r: &ChainRequest) -> Result<ExtractedTopic> {
    let c = tree.chain(path, r)?;
    Ok(ExtractedTopic {
        topic: r.topic.clone(),
        type_name: tf_chain::CHAIN_TYPE_NAME.to_string(),
        trajectory: c.composed.trajectory,
        messages: c.edges_read,
        invalid_dropped: c.composed.outside_span,
        duplicate_stamps: 0,
        rows: RowAudit {
            read: c.edges_read,
            outside_tf_span: c.composed.outside_span,
            ..RowAudit::default()
        },
        geodetic_origin: None,
    })
}

/// The plain topics' trajectories once the pass is done: sorted and cleaned (every dropped row
/// counted), geodetic ones moved to ENU around the given origin or the first valid fix; a topic
/// without a message gets an empty trajectory of its kind.
fn finish_topics(
    accumulators: Vec<Option<Accumulator>>,
    unique: &[&str],
    channels: &[ChannelInfo],
    options: &ExtractOptions,
) -> Result<Vec<ExtractedTopic>> {
    let positions_only = |topic: &str| options.positions_only.iter().any(|t| t == topic);
    let mut accumulators: Vec<Accumulator> = accumulators
        .into_iter()
        .zip(unique)
        .map(|(acc, topic)| {
            acc.or_else(|| {
                channels
                    .iter()
                    .filter(|c| c.topic == *topic)
                    .find_map(channel_kind)
                    .map(|(kind, _)| Accumulator::new(kind, positions_only(topic)))
            })
            .ok_or_else(|| Error::InvalidArgument(format!("{topic}: no readable channel")))
        })
        .collect::<Result<_>>()?;
    // Invalid samples (NO_FIX, NaN) never reach the trajectory; `clean` counts the rest.
    let audits: Vec<RowAudit> = accumulators
        .iter_mut()
        .map(|a| {
            let mut audit = a.trajectory.clean();
            audit.read = a.messages;
            audit.not_finite += a.invalid_dropped;
            audit
        })
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
    Ok(accumulators
        .into_iter()
        .zip(audits)
        .zip(unique)
        .map(|((mut acc, rows), topic)| {
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
            ExtractedTopic {
                topic: topic.to_string(),
                type_name: acc.kind.type_name().to_string(),
                trajectory: acc.trajectory,
                messages: acc.messages,
                invalid_dropped: rows.not_finite + rows.out_of_range,
                duplicate_stamps: rows.duplicate_stamp,
                rows,
                geodetic_origin,
            }
        })
        .collect())
}

/// The extracted topics in the order they were requested (`plain[i]` is `unique[i]`'s); a topic
/// requested twice is cloned.
fn in_request_order(
    topics: &[String],
    unique: &[&str],
    plain: Vec<ExtractedTopic>,
    chains: &[ExtractedTopic],
) -> Vec<ExtractedTopic> {
    let mut done: Vec<Option<ExtractedTopic>> = plain.into_iter().map(Some).collect();
    let mut out = Vec::with_capacity(topics.len());
    for t in topics {
        if let Some(c) = chains.iter().find(|c| &c.topic == t) {
            out.push(c.clone());
            continue;
        }
        let i = unique.iter().position(|u| u == t).unwrap_or(0);
        let next = match done.get_mut(i).and_then(Option::take) {
            Some(x) => x,
            None => match out.iter().find(|x: &&ExtractedTopic| &x.topic == t) {
                Some(x) => x.clone(),
                None => continue,
            },
        };
        out.push(next);
    }
    out
}

//! Which sources a mission holds, which one is the reference, and which file each came from.
//!
//! **Sources.** With `--source [NAME=]TOPIC` flags, those (TF chains `/tf:PARENT:CHILD` included).
//! Without, every readable pose or position topic of the recording (what `trajdrift topics` marks
//! `yes`), plus the preset's estimates (a preset may name TF chains, which no topic listing shows).
//!
//! **The reference.** `--reference TOPIC`; else the preset's (`--preset`, or the one built-in preset
//! the recording matches, said in a note); else the position-only topic (PointStamped, NavSatFix:
//! a prism, a GNSS) with the most messages, else the topic with the most messages — said in a note,
//! with the flag that changes it. A curator auditing an unknown recording gets an answer at once.
//!
//! **Files.** A mission given as several files or a folder is read as one recording; each topic's
//! file is looked up in the files' indexes (no pass over the messages), so that `restamp` can take the
//! file a source came from as its clock domain (GrandTour records one bag per computer or sensor).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::decode::message_kind;
use crate::error::{Error, Result};
use crate::eval::config::{NamedInput, TrajectoryInput};
use crate::eval::preset::{matching, Preset};
use crate::sources::TopicInfo;

/// What the user asked for.
#[derive(Debug, Clone, Default)]
pub struct SourceRequest {
    /// `--reference TOPIC`.
    pub reference: Option<String>,
    /// `--source [NAME=]TOPIC`, in order.
    pub sources: Vec<String>,
    /// `--preset NAME|FILE`.
    pub preset: Option<String>,
}

/// The sources found.
#[derive(Debug, Clone)]
pub struct Discovered {
    pub reference: NamedInput,
    /// Every other source, in the order given (or of the recording's topic list).
    pub sources: Vec<NamedInput>,
    /// The files of the mission, in name order (one entry for a single recording).
    pub files: Vec<PathBuf>,
    /// Topic → the files holding it (a topic in several files of a mission is read from all).
    pub topic_files: BTreeMap<String, Vec<PathBuf>>,
    /// What the user should know about the choices made (the reference picked, sources skipped).
    pub notes: Vec<String>,
}

impl Discovered {
    /// The topic of an input (`""` for a file, which an audit never has).
    pub fn topic(input: &NamedInput) -> &str {
        match &input.input {
            TrajectoryInput::Topic(t) => t,
            TrajectoryInput::TumFile(_) => "",
        }
    }

    /// The one file a topic came from (a TF chain `/tf:…`: the file of `/tf`), when it is one.
    pub fn file_of(&self, topic: &str) -> Option<&Path> {
        let key = if topic.starts_with("/tf:") {
            "/tf"
        } else {
            topic
        };
        match self.topic_files.get(key).map(Vec::as_slice) {
            Some([one]) => Some(one.as_path()),
            _ => None,
        }
    }
}

/// The files a RECORDING argument stands for: a folder of recordings (not a rosbag2 folder) is its
/// recordings, anything else itself.
pub fn expand_files(recordings: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for r in recordings {
        if r.is_dir() && !r.join("metadata.yaml").is_file() {
            out.extend(crate::sources::open::recordings_in(r)?);
        } else {
            out.push(r.clone());
        }
    }
    Ok(out)
}

/// Topic → files, from each file's index (or one pass that decodes nothing, without an index).
pub(crate) fn topic_files(files: &[PathBuf]) -> Result<BTreeMap<String, Vec<PathBuf>>> {
    let mut map: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    for f in files {
        let rec = crate::sources::open::open_recording(f)?;
        let channels = match rec.known_channels() {
            Some(c) => c,
            None => rec.channel_counts()?.0,
        };
        for c in channels {
            let e = map.entry(c.topic).or_default();
            if !e.contains(f) {
                e.push(f.clone());
            }
        }
    }
    Ok(map)
}

/// Position-only message types (a prism, a GNSS): the usual references.
fn position_only(t: &TopicInfo) -> bool {
    message_kind(&t.type_name).is_some_and(|k| !k.has_orientation())
}

/// Finds the reference and the sources of `recordings` for `request`.
pub fn discover(recordings: &[PathBuf], request: &SourceRequest) -> Result<Discovered> {
    if recordings.is_empty() {
        return Err(Error::InvalidArgument(
            "give the RECORDING (a file, several files of one mission, or a mission folder)".into(),
        ));
    }
    let files = expand_files(recordings)?;
    let topics: Vec<TopicInfo> = crate::sources::open_all(recordings)?.topics()?;
    let readable: Vec<&TopicInfo> = topics.iter().filter(|t| t.readable).collect();
    let mut notes = Vec::new();
    let preset = pick_preset(request, &topics, &mut notes)?;
    let given: Vec<NamedInput> = request
        .sources
        .iter()
        .map(|s| NamedInput::topic(s))
        .collect();
    let user_reference = request.reference.as_deref().map(NamedInput::topic);
    let (reference, preset_sources) = match &preset {
        Some(p) => {
            let s = p.select(&recordings[0], &topics, user_reference.clone(), Vec::new())?;
            (s.reference, s.estimates)
        }
        None => match user_reference {
            Some(r) => (r, Vec::new()),
            None => (
                pick_reference(&recordings[0], &readable, &mut notes)
                    .map_err(|e| cut_short(recordings, "no pose or position topic").unwrap_or(e))?,
                Vec::new(),
            ),
        },
    };
    let reference_topic = Discovered::topic(&reference).to_string();
    let sources = pick_sources(&reference_topic, given, preset_sources, &readable);
    if sources.is_empty() {
        let only = format!("only the reference {reference_topic} as a pose or position topic");
        return Err(cut_short(recordings, &only).unwrap_or_else(|| Error::InvalidArgument(format!(
            "{}: only the reference {reference_topic} is a pose or position topic; an audit needs two sources or more (give --source TOPIC, e.g. a TF chain /tf:PARENT:CHILD)",
            recordings[0].display()
        ))));
    }
    let mut names: BTreeMap<String, usize> = BTreeMap::new();
    for s in std::iter::once(&reference).chain(&sources) {
        *names.entry(s.name.clone()).or_default() += 1;
    }
    if let Some((dup, _)) = names.iter().find(|(_, n)| **n > 1) {
        return Err(Error::InvalidArgument(format!(
            "two sources are named `{dup}`; name them with --source NAME=TOPIC"
        )));
    }
    Ok(Discovered {
        reference,
        sources,
        topic_files: topic_files(&files)?,
        files,
        notes,
    })
}

/// When `recordings` is one recording cut short: the error saying so (a failure, not a usage error),
/// for a discovery that found too little in it, since what is missing may be past the cut. `found`
/// says what was found before it.
fn cut_short(recordings: &[PathBuf], found: &str) -> Option<Error> {
    let [one] = recordings else {
        return None;
    };
    let rec = crate::sources::open::open_recording(one).ok()?;
    let (_, truncated_at) = crate::sources::tf_frames::scan(&*rec, &|_| {}).ok()?;
    Some(Error::Damaged {
        path: one.clone(),
        offset: truncated_at?,
        detail: format!("the recording is cut short there, and {found} was found before"),
    })
}

/// The preset: the one asked, or the one the recording matches when no reference was given.
fn pick_preset(
    request: &SourceRequest,
    topics: &[TopicInfo],
    notes: &mut Vec<String>,
) -> Result<Option<Preset>> {
    Ok(match &request.preset {
        Some(p) => Some(Preset::load(p)?),
        None if request.reference.is_none() => match matching(topics).as_slice() {
            [one] => {
                notes.push(format!(
                    "preset {one}: the recording matches it, its reference is used (choose with --preset or --reference)"
                ));
                Some(Preset::load(one)?)
            }
            _ => None,
        },
        None => None,
    })
}

/// The reference when none was given: the position-only topic with the most messages, else the
/// topic with the most.
fn pick_reference(
    recording: &Path,
    readable: &[&TopicInfo],
    notes: &mut Vec<String>,
) -> Result<NamedInput> {
    fn by_count(pool: Vec<&TopicInfo>) -> Option<&TopicInfo> {
        pool.into_iter()
            .max_by_key(|t| (t.message_count, std::cmp::Reverse(t.topic.clone())))
    }
    let positions: Vec<&TopicInfo> = readable
        .iter()
        .copied()
        .filter(|t| position_only(t))
        .collect();
    let picked = by_count(positions)
        .or_else(|| by_count(readable.to_vec()))
        .ok_or_else(|| {
            Error::InvalidArgument(format!(
                "{}: no pose or position topic to audit (see `trajdrift topics`); give --reference TOPIC and --source TOPIC",
                recording.display()
            ))
        })?;
    notes.push(format!(
        "reference {}: picked as the {} with the most messages (choose with --reference TOPIC)",
        picked.topic,
        if position_only(picked) {
            "position-only topic"
        } else {
            "topic"
        }
    ));
    Ok(NamedInput::topic(&picked.topic))
}

/// The sources: those given, else the preset's (named as the dataset names them) and then every
/// readable topic; the reference and repeated topics left out.
fn pick_sources(
    reference_topic: &str,
    given: Vec<NamedInput>,
    preset_sources: Vec<NamedInput>,
    readable: &[&TopicInfo],
) -> Vec<NamedInput> {
    let mut sources: Vec<NamedInput> = Vec::new();
    let push = |s: NamedInput, sources: &mut Vec<NamedInput>| {
        let t = Discovered::topic(&s).to_string();
        if t != reference_topic && !sources.iter().any(|o| Discovered::topic(o) == t) {
            sources.push(s);
        }
    };
    if given.is_empty() {
        for s in preset_sources {
            push(s, &mut sources);
        }
        let mut rest: Vec<&str> = readable.iter().map(|t| t.topic.as_str()).collect();
        rest.sort_unstable();
        for t in rest {
            push(NamedInput::topic(t), &mut sources);
        }
    } else {
        for s in given {
            push(s, &mut sources);
        }
    }
    sources
}

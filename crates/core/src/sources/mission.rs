//! A mission stored as several recordings (GrandTour ships one ROS 1 bag per sensor group, all on one
//! time base) read as one [`Recording`].
//!
//! Channels of the files are keyed by (topic, type, message encoding): a topic in several files is one
//! channel whose messages come from each of them, so extraction merges them (trajectories are sorted by
//! stamp at the end of the pass) and `/tf` + `/tf_static` edges are collected across all files. A pass
//! reads each file once, one after the other: memory is what one file's pass needs plus the samples
//! kept. Files holding `/tf_static` are read first, so the TF tree's static part is known before the
//! dynamic edges arrive (as a recorder that latches `/tf_static` at the start would have it). A topic
//! with different types in two files is refused when it is read, naming both files. An extraction
//! whose topics each live in one file and that needs no TF reads the files holding them side by
//! side instead, each on its own ([`Recording::parts`]; `crate::sources::extract`): the same
//! trajectories in the time of the largest file, memory one pass's per file being read.

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::error::{Error, Result};
use crate::sources::recording::{
    ChannelInfo, MessageRef, OnMessage, Recording, Select, StreamOutcome,
};
use crate::sources::{Progress, Warning};

/// One recording of a mission.
pub type Part = Box<dyn Recording + Send + Sync>;

/// Several recordings read as one.
pub struct Mission {
    /// What messages name: the mission folder, or the first file.
    path: PathBuf,
    /// In reading order (files with `/tf_static` first, then as given).
    parts: Vec<Part>,
    /// The part and offset where the last pass found a file cut short.
    truncated: Mutex<Option<(usize, u64)>>,
}

/// (topic, schema name, message encoding): what makes channels of several files one.
type Key = (String, String, String);

fn key(c: &ChannelInfo) -> Key {
    (
        c.topic.clone(),
        c.schema_name.clone(),
        c.message_encoding.clone(),
    )
}

/// Mission channels assigned while files are read: ids in order of first appearance.
#[derive(Default)]
struct Channels {
    list: Vec<ChannelInfo>,
    by_key: HashMap<Key, u16>,
    /// Global id → the part it was first seen in (for the type-conflict message).
    first_part: Vec<usize>,
}

impl Channels {
    fn global(&mut self, part: usize, c: &ChannelInfo) -> Result<u16> {
        if let Some(&id) = self.by_key.get(&key(c)) {
            return Ok(id);
        }
        let id = u16::try_from(self.list.len()).map_err(|_| {
            Error::InvalidArgument("a mission with more than 65536 channels".into())
        })?;
        self.by_key.insert(key(c), id);
        self.list.push(ChannelInfo { id, ..c.clone() });
        self.first_part.push(part);
        Ok(id)
    }

    /// Another channel of the same topic with another type, if any. ROS 1 and ROS 2 spellings of
    /// one type (`nav_msgs/Odometry`, `nav_msgs/msg/Odometry`) are the same type.
    fn conflict(&self, c: &ChannelInfo) -> Option<&ChannelInfo> {
        let name = |c: &ChannelInfo| c.schema_name.replace("/msg/", "/");
        self.list
            .iter()
            .find(|o| o.topic == c.topic && o.id != c.id && name(o) != name(c))
    }
}

impl Mission {
    /// A mission of `parts`, named `path` in messages. Parts holding `/tf_static` (by their index)
    /// are moved to the front.
    pub fn new(path: &Path, parts: Vec<Part>) -> Result<Mission> {
        if parts.is_empty() {
            return Err(Error::InvalidArgument(format!(
                "{}: no recording (.mcap, .bag or rosbag2 folder) in the mission",
                path.display()
            )));
        }
        let has_static = |p: &Part| {
            p.known_channels()
                .is_some_and(|cs| cs.iter().any(crate::sources::tf_chain::is_static_channel))
        };
        let (mut parts, rest): (Vec<Part>, Vec<Part>) = parts.into_iter().partition(has_static);
        parts.extend(rest);
        Ok(Mission {
            path: path.to_path_buf(),
            parts,
            truncated: Mutex::new(None),
        })
    }

    /// [`Recording::pass`], telling `on_message` which file (its index in [`Mission::parts`]) each
    /// message came from: what a copy needs that treats each file's messages by the file's clock.
    pub fn pass_parts(
        &self,
        select: Select<'_>,
        progress: Progress<'_>,
        on_message: &mut dyn FnMut(usize, &ChannelInfo, &MessageRef<'_>) -> Result<()>,
    ) -> Result<StreamOutcome> {
        // Both callbacks of a file's pass need the channels: `select` adds to them, `on_message` reads.
        let channels = RefCell::new(Channels::default());
        // Global id → selected; asked once per mission channel.
        let mut selected: HashMap<u16, bool> = HashMap::new();
        let mut out = StreamOutcome::default();
        let mut done = 0u64;
        let failure: RefCell<Option<Error>> = RefCell::new(None);
        *self.truncated.lock().unwrap_or_else(|e| e.into_inner()) = None;
        for (i, part) in self.parts.iter().enumerate() {
            // Local id → global id, for this file's pass.
            let local: RefCell<HashMap<u16, u16>> = RefCell::new(HashMap::new());
            let before = done;
            let o = part.pass(
                &mut |c| {
                    let mut chs = channels.borrow_mut();
                    let Ok(id) = chs.global(i, c) else {
                        return false;
                    };
                    local.borrow_mut().insert(c.id, id);
                    let g = chs.list[id as usize].clone();
                    let wanted = *selected.entry(id).or_insert_with(|| select(&g));
                    let mut f = failure.borrow_mut();
                    if wanted && f.is_none() && chs.conflict(&g).is_some() {
                        *f = Some(self.type_conflict(&chs, &g, i));
                    }
                    wanted
                },
                &|n| progress(before + n),
                &mut |c, m| {
                    if let Some(e) = failure.borrow_mut().take() {
                        return Err(e);
                    }
                    let id = local.borrow().get(&c.id).copied().unwrap_or(c.id);
                    let chs = channels.borrow();
                    on_message(
                        i,
                        &chs.list[id as usize],
                        &MessageRef {
                            channel_id: id,
                            ..*m
                        },
                    )
                },
            )?;
            if let Some(e) = failure.borrow_mut().take() {
                return Err(e);
            }
            let mut chs = channels.borrow_mut();
            for c in &o.channels {
                let id = chs.global(i, c)?;
                *out.message_counts.entry(id).or_default() +=
                    o.message_counts.get(&c.id).copied().unwrap_or(0);
            }
            if let Some(offset) = o.truncated_at {
                out.truncated_at = Some(done + offset);
                *self.truncated.lock().unwrap_or_else(|e| e.into_inner()) = Some((i, offset));
            }
            done += part.recording_size();
            progress(done);
        }
        let channels = channels.into_inner();
        out.channels = channels.list;
        out.bytes_read = done;
        Ok(out)
    }

    fn type_conflict(&self, channels: &Channels, c: &ChannelInfo, part: usize) -> Error {
        let other = channels.conflict(c);
        let (other_type, other_part) = other
            .map(|o| (o.schema_name.as_str(), channels.first_part[o.id as usize]))
            .unwrap_or(("?", part));
        Error::Mission {
            path: self.path.clone(),
            detail: format!(
            "topic {} has type {} in {} but {} in {}; a topic must have one type across a mission's files (pass only the files that agree)",
            c.topic,
            other_type,
            self.parts[other_part].path().display(),
            c.schema_name,
            self.parts[part].path().display(),
        ),
        }
    }
}

impl Recording for Mission {
    fn path(&self) -> &Path {
        &self.path
    }

    fn recording_size(&self) -> u64 {
        self.parts.iter().map(|p| p.recording_size()).sum()
    }

    fn channel_counts(&self) -> Result<(Vec<ChannelInfo>, HashMap<u16, u64>)> {
        let mut channels = Channels::default();
        let mut counts: HashMap<u16, u64> = HashMap::new();
        for (i, p) in self.parts.iter().enumerate() {
            let (cs, n) = p.channel_counts()?;
            for c in &cs {
                let id = channels.global(i, c)?;
                *counts.entry(id).or_default() += n.get(&c.id).copied().unwrap_or(0);
            }
        }
        Ok((channels.list, counts))
    }

    fn known_channels(&self) -> Option<Vec<ChannelInfo>> {
        let mut channels = Channels::default();
        for (i, p) in self.parts.iter().enumerate() {
            for c in &p.known_channels()? {
                channels.global(i, c).ok()?;
            }
        }
        // A topic with two types is reported by the pass, which names both files.
        if channels.list.iter().any(|c| channels.conflict(c).is_some()) {
            return None;
        }
        Some(channels.list)
    }

    fn pass(
        &self,
        select: Select<'_>,
        progress: Progress<'_>,
        on_message: OnMessage<'_>,
    ) -> Result<StreamOutcome> {
        self.pass_parts(select, progress, &mut |_, c, m| on_message(c, m))
    }

    /// The recordings, in reading order.
    fn parts(&self) -> &[Part] {
        &self.parts
    }

    fn truncation_warning(&self, offset: u64) -> Warning {
        match *self.truncated.lock().unwrap_or_else(|e| e.into_inner()) {
            Some((i, local)) => self.parts[i].truncation_warning(local),
            None => Warning {
                code: crate::diag::WarningCode::TruncatedRecording,
                message: format!(
                    "{}: recording cut short at byte {offset}; read up to the last complete record",
                    self.path.display()
                ),
            },
        }
    }
}

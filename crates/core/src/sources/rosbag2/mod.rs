//! rosbag2 folders (`metadata.yaml` plus one or several split files, storage `mcap` or `sqlite3`)
//! as a [`Source`](crate::sources::Source).
//!
//! Channels come from `metadata.yaml` (one per topic, ids in its order, so they are the same in
//! every split file); the files are read one after the other in one pass: MCAP files through the
//! MCAP stream, `.db3` files through [`sqlite`].

pub(crate) mod metadata;
pub(crate) mod schemas;
pub(crate) mod sqlite;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::sources::mcap::for_each_message;
use crate::sources::recording::{
    ChannelInfo, MessageRef, OnMessage, Recording, Select, StreamOutcome,
};
use crate::sources::Progress;

use metadata::Metadata;

/// The storage plugin of a rosbag2 folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    Mcap,
    Sqlite3,
}

/// A rosbag2 folder. Opening reads `metadata.yaml` and checks that every file it names exists.
#[derive(Debug, Clone)]
pub struct Rosbag2Source {
    dir: PathBuf,
    storage: Storage,
    files: Vec<PathBuf>,
    channels: Vec<ChannelInfo>,
    counts: HashMap<u16, u64>,
    size: u64,
}

impl Rosbag2Source {
    /// Opens the folder `dir`: [`Error::Rosbag2`] for a missing or bad `metadata.yaml`, an
    /// unsupported storage or compression, or a split file it names that is missing.
    pub fn open(dir: &Path) -> Result<Rosbag2Source> {
        let bad = |detail: String| Error::Rosbag2 {
            path: dir.to_path_buf(),
            detail,
        };
        let meta: Metadata = metadata::read(dir)?;
        let storage = match meta.storage_identifier.as_str() {
            "mcap" => Storage::Mcap,
            "sqlite3" => Storage::Sqlite3,
            other => {
                return Err(bad(format!(
                    "storage `{other}` is not supported (mcap, sqlite3); convert it with `ros2 bag convert`"
                )))
            }
        };
        if let Some(c) = meta.compression_format.as_deref().filter(|c| !c.is_empty()) {
            return Err(bad(format!(
                "compression `{c}` is not supported; decompress it with `ros2 bag convert` first"
            )));
        }
        if meta.relative_file_paths.is_empty() {
            return Err(bad(
                "metadata.yaml names no file; re-create it with `ros2 bag reindex`".into(),
            ));
        }
        let mut files = Vec::new();
        let mut size = 0;
        for f in &meta.relative_file_paths {
            let p = dir.join(f);
            let len = std::fs::metadata(&p).map(|m| m.len()).map_err(|_| {
                bad(format!(
                    "metadata.yaml names {f}, which is missing; restore the file, or remove it from metadata.yaml (`ros2 bag reindex`)"
                ))
            })?;
            size += len;
            files.push(p);
        }
        let definitions = schemas::definitions(storage, &files);
        let mut channels = Vec::new();
        let mut counts = HashMap::new();
        for (i, t) in meta.topics_with_message_count.iter().enumerate() {
            let id = u16::try_from(i).map_err(|_| bad("more than 65536 topics".into()))?;
            counts.insert(id, t.message_count);
            channels.push(ChannelInfo {
                id,
                topic: t.topic_metadata.name.clone(),
                schema_name: t.topic_metadata.type_name.clone(),
                schema_encoding: "ros2msg".into(),
                message_encoding: t.topic_metadata.serialization_format.clone(),
                schema_data: definitions
                    .get(&t.topic_metadata.type_name)
                    .cloned()
                    .unwrap_or_default(),
            });
        }
        Ok(Rosbag2Source {
            dir: dir.to_path_buf(),
            storage,
            files,
            channels,
            counts,
            size,
        })
    }
}

impl Recording for Rosbag2Source {
    fn recording_size(&self) -> u64 {
        self.size
    }

    fn channel_counts(&self) -> Result<(Vec<ChannelInfo>, HashMap<u16, u64>)> {
        Ok((self.channels.clone(), self.counts.clone()))
    }

    fn path(&self) -> &Path {
        &self.dir
    }

    fn known_channels(&self) -> Option<Vec<ChannelInfo>> {
        Some(self.channels.clone())
    }

    fn pass(
        &self,
        select: Select<'_>,
        progress: Progress<'_>,
        on_message: OnMessage<'_>,
    ) -> Result<StreamOutcome> {
        let selected: Vec<bool> = self.channels.iter().map(&mut *select).collect();
        let by_topic: HashMap<&str, usize> = self
            .channels
            .iter()
            .enumerate()
            .map(|(i, c)| (c.topic.as_str(), i))
            .collect();
        let mut out = StreamOutcome {
            channels: self.channels.clone(),
            message_counts: self.counts.clone(),
            ..Default::default()
        };
        let mut done = 0u64;
        for file in &self.files {
            let before = done;
            let file_progress = |n: u64| progress(before + n);
            match self.storage {
                Storage::Mcap => {
                    let o = for_each_message(
                        file,
                        |c| by_topic.get(c.topic.as_str()).is_some_and(|&i| selected[i]),
                        &file_progress,
                        |c, m| {
                            // Selected channels are in `by_topic`.
                            let Some(&i) = by_topic.get(c.topic.as_str()) else {
                                return Ok(());
                            };
                            let g = &self.channels[i];
                            on_message(
                                g,
                                &MessageRef {
                                    channel_id: g.id,
                                    ..*m
                                },
                            )
                        },
                    )?;
                    if o.truncated_at.is_some() {
                        out.truncated_at = Some(done + o.bytes_read);
                    }
                }
                Storage::Sqlite3 => {
                    sqlite::for_each_message(file, &self.channels, &selected, on_message)?;
                }
            }
            done += std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
            progress(done);
        }
        out.bytes_read = done;
        Ok(out)
    }
}

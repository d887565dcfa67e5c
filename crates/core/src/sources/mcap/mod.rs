//! MCAP recordings (ROS 2: `cdr` messages with `ros2msg` schemas; ROS 1: `ros1` messages with
//! `ros1msg` schemas) as a `Source`.
//!
//! [`stream`] is the single streaming pass everything is built on, [`summary`] the optional index at
//! the end of the file; this file turns selected channels into trajectories.

pub mod lengths;
pub mod stream;
pub mod summary;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::decode::MessageKind;
use crate::error::{Error, Result};
use crate::sources::extract;
use crate::sources::recording::{ChannelInfo, OnMessage, Recording, Select, StreamOutcome};
use crate::sources::{Progress, Warning};

pub use stream::for_each_message;
pub use summary::{read_summary, SummaryInfo};

/// An MCAP file on disk. Opening checks the magic; nothing else is read until asked.
#[derive(Debug, Clone)]
pub struct McapSource {
    path: PathBuf,
    size: u64,
    /// The summary's channels, read once (the fail-fast topic check and the evaluation's look at the
    /// reference's type both ask).
    channels: std::sync::OnceLock<Option<Vec<ChannelInfo>>>,
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
            channels: std::sync::OnceLock::new(),
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The kind of a channel when trajdrift can decode it (a supported schema with `cdr` or `ros1`
/// messages).
pub fn readable_kind(c: &ChannelInfo) -> Option<MessageKind> {
    extract::channel_kind(c).map(|(kind, _)| kind)
}

impl Recording for McapSource {
    fn recording_size(&self) -> u64 {
        self.size
    }

    fn channel_counts(&self) -> Result<(Vec<ChannelInfo>, HashMap<u16, u64>)> {
        Ok(match read_summary(&self.path) {
            Some(SummaryInfo {
                channels,
                message_counts: Some(counts),
            }) => (channels, counts),
            _ => {
                let outcome = for_each_message(&self.path, |_| false, &|_| {}, |_, _| Ok(()))?;
                (outcome.channels, outcome.message_counts)
            }
        })
    }

    fn path(&self) -> &Path {
        &self.path
    }

    fn known_channels(&self) -> Option<Vec<ChannelInfo>> {
        self.channels
            .get_or_init(|| read_summary(&self.path).map(|s| s.channels))
            .clone()
    }

    fn pass(
        &self,
        select: Select<'_>,
        progress: Progress<'_>,
        on_message: OnMessage<'_>,
    ) -> Result<StreamOutcome> {
        for_each_message(&self.path, select, progress, on_message)
    }

    fn truncation_warning(&self, offset: u64) -> Warning {
        Warning {
            code: crate::diag::WarningCode::TruncatedRecording,
            message: format!(
                "{}: recording cut short at byte {offset} (no footer; the recorder probably stopped abruptly); read up to the last complete record",
                self.path.display()
            ),
        }
    }
}

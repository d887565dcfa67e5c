//! What every stored recording shares, whatever its format: its channels ([`ChannelInfo`]), a message
//! borrowed during a pass ([`MessageRef`]), what a pass learned ([`StreamOutcome`]) and the
//! [`Recording`] trait itself.
//!
//! MCAP files, ROS 1 bags, rosbag2 folders and multi-file missions all implement [`Recording`]; this
//! module belongs to none of them, so no storage format is the others' lingua franca and the readers,
//! extraction (`crate::sources::extract`) and TF ([`crate::sources::tf_chain`]) depend on it, not on
//! each other.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use crate::error::Result;
use crate::sources::{Progress, Warning};

/// One channel of a recording, with its schema's name.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ChannelInfo {
    /// Channel id, unique within the recording.
    pub id: u16,
    pub topic: String,
    /// Schema name, e.g. `geometry_msgs/msg/PoseStamped`; empty for schemaless channels.
    pub schema_name: String,
    /// Schema encoding, e.g. `ros2msg`; empty for schemaless channels.
    pub schema_encoding: String,
    /// Message encoding, e.g. `cdr`.
    pub message_encoding: String,
    /// The schema's text when the recording carries it (a ROS 1 connection's `message_definition`, a
    /// rosbag2 message definition, an MCAP schema record); empty when unknown. Shared, not copied,
    /// between the clones of a channel. Only `--annotate` needs it (to write the channel out).
    pub schema_data: Arc<[u8]>,
}

/// A message on a selected channel, borrowed from the reader's buffer.
#[derive(Debug, Clone, Copy)]
pub struct MessageRef<'a> {
    pub channel_id: u16,
    pub sequence: u32,
    /// Nanoseconds; when the recorder received the message.
    pub log_time: u64,
    /// Nanoseconds; when the publisher sent it.
    pub publish_time: u64,
    /// The serialized message, in the channel's message encoding (CDR, ROS 1).
    pub data: &'a [u8],
}

/// What one pass learned about the whole recording.
#[derive(Debug, Clone, Default)]
pub struct StreamOutcome {
    /// Every channel, in the order of first appearance (a repeated channel record is listed once).
    pub channels: Vec<ChannelInfo>,
    /// Messages per channel id, selected or not.
    pub message_counts: HashMap<u16, u64>,
    /// Bytes read from the recording.
    pub bytes_read: u64,
    /// `Some(offset)` when the recording ended inside a record (or before its end marker): everything
    /// before was read, `offset` is where it stops.
    pub truncated_at: Option<u64>,
}

/// Asked once per channel whether its messages are wanted.
pub type Select<'a> = &'a mut dyn FnMut(&ChannelInfo) -> bool;
/// Gets every message of a selected channel; an error stops the pass.
pub type OnMessage<'a> = &'a mut dyn FnMut(&ChannelInfo, &MessageRef<'_>) -> Result<()>;

/// A recording read by one streaming pass in file order.
pub trait Recording {
    /// What error messages name: the file or folder.
    fn path(&self) -> &Path;
    /// Size of the recording in bytes (for progress bars and the report).
    fn recording_size(&self) -> u64;
    /// Every channel with its message count: from an index when the recording has one, else from a
    /// pass that decodes nothing.
    fn channel_counts(&self) -> Result<(Vec<ChannelInfo>, HashMap<u16, u64>)>;
    /// The channels when an index lists them without a pass (to fail fast on a wrong topic).
    fn known_channels(&self) -> Option<Vec<ChannelInfo>>;
    /// One pass over the messages. Channel ids must be unique across the whole recording.
    fn pass(
        &self,
        select: Select<'_>,
        progress: Progress<'_>,
        on_message: OnMessage<'_>,
    ) -> Result<StreamOutcome>;
    /// The recordings this one reads one after the other (a multi-file mission), empty for a single
    /// recording: an extraction that needs nothing across them may read them side by side.
    fn parts(&self) -> &[Box<dyn Recording + Send + Sync>] {
        &[]
    }
    /// The warning for a recording cut short at byte `offset`.
    fn truncation_warning(&self, offset: u64) -> Warning {
        Warning {
            code: crate::diag::WarningCode::TruncatedRecording,
            message: format!(
                "{}: recording cut short at byte {offset} (the recorder probably stopped abruptly); read up to the last complete record",
                self.path().display()
            ),
        }
    }
}

/// A boxed recording (what [`crate::sources::open::open_recording`] returns) is a recording.
impl<R: Recording + ?Sized> Recording for Box<R> {
    fn path(&self) -> &Path {
        (**self).path()
    }
    fn recording_size(&self) -> u64 {
        (**self).recording_size()
    }
    fn channel_counts(&self) -> Result<(Vec<ChannelInfo>, HashMap<u16, u64>)> {
        (**self).channel_counts()
    }
    fn known_channels(&self) -> Option<Vec<ChannelInfo>> {
        (**self).known_channels()
    }
    fn pass(
        &self,
        select: Select<'_>,
        progress: Progress<'_>,
        on_message: OnMessage<'_>,
    ) -> Result<StreamOutcome> {
        (**self).pass(select, progress, on_message)
    }
    fn parts(&self) -> &[Box<dyn Recording + Send + Sync>] {
        (**self).parts()
    }
    fn truncation_warning(&self, offset: u64) -> Warning {
        (**self).truncation_warning(offset)
    }
}

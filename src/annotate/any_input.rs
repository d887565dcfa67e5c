//! The copy pass for inputs that are not one MCAP file: ROS 1 bags, rosbag2 folders (MCAP or sqlite3
//! storage), missions of several files, or no recording at all (text trajectories).
//!
//! Every message of the input is streamed through [`Recording::pass`] into an `mcap::Writer` with its
//! bytes, encoding and times unchanged: ROS 1 messages stay `ros1` with their connection's
//! `message_definition` as a `ros1msg` schema (what `mcap convert` writes, and what Foxglove reads),
//! rosbag2 messages stay `cdr` with their `ros2msg` definitions. A mission's channels all go into the
//! one output, in the order its files are read (MCAP readers order by log time through the index).
//! Memory follows the largest message and the writer's chunk, not the input.

use std::collections::hash_map::Entry;
use std::collections::{BTreeMap, HashMap};
use std::io::{Seek, Write};
use std::path::Path;

use mcap::records::MessageHeader;
use mcap::{McapError, Writer};

use crate::annotate::copy::{Annotations, CopyOutcome, InputChannel};
use crate::error::{Error, Result};
use crate::sources::recording::{ChannelInfo, Recording};
use crate::sources::Progress;

/// The MCAP profile for channels of `encoding`: `ros1` or `ros2`, empty when mixed or unknown.
pub fn profile(channels: &[ChannelInfo]) -> &'static str {
    let all = |e: &str| !channels.is_empty() && channels.iter().all(|c| c.message_encoding == e);
    if all("ros1") {
        "ros1"
    } else if all("cdr") {
        "ros2"
    } else {
        ""
    }
}

/// What [`copy_recording`] copies.
#[derive(Clone, Copy)]
pub enum CopyInput<'a> {
    /// No recording (text trajectories): the annotations alone.
    Nothing,
    /// One recording (a mission read as one is one too: its files are not told apart).
    One(&'a dyn Recording),
    /// A mission whose files are told apart: each message's file index goes to
    /// [`Annotations::rewrite`].
    Parts(&'a crate::sources::mission::Mission),
}

/// Copies every message of `input` into a new MCAP on `out`, calling `annotations` along the way.
/// Returns the sink (to flush and sync).
pub fn copy_recording<W: Write + Seek, A: Annotations<W>>(
    input: CopyInput<'_>,
    out: W,
    output_path: &Path,
    options: mcap::WriteOptions,
    profile: &str,
    annotations: &mut A,
    progress: Progress<'_>,
) -> Result<(CopyOutcome, W)> {
    let write_err = |e: McapError| Error::Output {
        path: output_path.to_path_buf(),
        detail: e.to_string(),
    };
    let mut w: Writer<W> = options.profile(profile).create(out).map_err(write_err)?;
    annotations.start(&mut w)?;
    let mut outcome = CopyOutcome::default();
    if !matches!(input, CopyInput::Nothing) {
        // (name, encoding, text) → schema id, counting up from 1 (the annotations count down).
        let mut schemas: HashMap<(String, String, Vec<u8>), u16> = HashMap::new();
        let mut channels: HashMap<u16, InputChannel> = HashMap::new();
        let mut sequences: HashMap<u16, u32> = HashMap::new();
        let mut on_message = |part: usize,
                              c: &ChannelInfo,
                              m: &crate::sources::recording::MessageRef<'_>|
         -> Result<()> {
            let channel = match channels.entry(c.id) {
                Entry::Occupied(e) => e.into_mut(),
                Entry::Vacant(e) => {
                    e.insert(add_channel(&mut w, &mut schemas, c).map_err(write_err)?)
                }
            };
            // Formats without sequence numbers (ROS 1 bags, rosbag2) get them counted per channel.
            let seq = sequences.entry(c.id).or_insert(0);
            *seq = seq.wrapping_add(1);
            let header = MessageHeader {
                channel_id: c.id,
                sequence: if m.sequence != 0 { m.sequence } else { *seq },
                log_time: m.log_time,
                publish_time: m.publish_time,
            };
            let log_time = super::copy::write_message(
                &mut w,
                annotations,
                part,
                channel,
                &header,
                m.data,
                output_path,
            )?;
            outcome.messages += 1;
            outcome.last_log_time = outcome.last_log_time.max(log_time);
            Ok(())
        };
        let o = match input {
            CopyInput::One(rec) => {
                Some(rec.pass(&mut |_| true, progress, &mut |c, m| on_message(0, c, m))?)
            }
            CopyInput::Parts(mission) => {
                Some(mission.pass_parts(&mut |_| true, progress, &mut on_message)?)
            }
            CopyInput::Nothing => None,
        };
        outcome.truncated_at = o.and_then(|o| o.truncated_at);
    }
    annotations.finish(&mut w)?;
    w.finish().map_err(write_err)?;
    Ok((outcome, w.into_inner()))
}

/// Writes channel `c` (its schema at its first use) to the copy, with its input id.
fn add_channel<W: Write + Seek>(
    w: &mut Writer<W>,
    schemas: &mut HashMap<(String, String, Vec<u8>), u16>,
    c: &ChannelInfo,
) -> std::result::Result<InputChannel, McapError> {
    let schema_id = schema_for(w, schemas, c)?;
    w.add_channel_with_id(
        c.id,
        schema_id,
        &c.topic,
        &c.message_encoding,
        &BTreeMap::new(),
    )?;
    Ok(InputChannel {
        id: c.id,
        schema_id,
        topic: c.topic.clone(),
        message_encoding: c.message_encoding.clone(),
        schema_name: c.schema_name.clone(),
        schema_data: c.schema_data.clone(),
    })
}

/// The schema id of `c`'s schema, written at its first use; 0 (none) for a schemaless channel.
fn schema_for<W: Write + Seek>(
    w: &mut Writer<W>,
    schemas: &mut HashMap<(String, String, Vec<u8>), u16>,
    c: &ChannelInfo,
) -> std::result::Result<u16, McapError> {
    if c.schema_name.is_empty() {
        return Ok(0);
    }
    let key = (
        c.schema_name.clone(),
        c.schema_encoding.clone(),
        c.schema_data.to_vec(),
    );
    if let Some(&id) = schemas.get(&key) {
        return Ok(id);
    }
    let id = u16::try_from(schemas.len() + 1).map_err(|_| McapError::TooManySchemas)?;
    w.add_schema_with_id(id, &c.schema_name, &c.schema_encoding, &c.schema_data)?;
    schemas.insert(key, id);
    Ok(id)
}

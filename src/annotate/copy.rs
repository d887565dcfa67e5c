//! The copy pass: every record of the input (schemas, channels, messages, attachments, metadata)
//! streamed into an `mcap::Writer` with the same ids, bytes and times, while an [`Annotations`]
//! adds its own channels and messages along the way.
//!
//! `mcap::sans_io::LinearReader` walks the input in file order, a chunk piece at a time, and the writer
//! re-chunks as it goes, so memory follows the largest record, not the file. The input's summary is not
//! copied: the writer writes a new one that also lists the new channels.

use std::collections::HashMap;
use std::io::{Seek, Write};
use std::path::Path;

use mcap::records::{op, MessageHeader, Record};
use mcap::sans_io::LinearReadEvent;
use mcap::{McapError, Writer};

use crate::error::{Error, Result};
use crate::sources::mcap::stream::{fill, open_linear};
use crate::sources::Progress;

/// What the copy pass tells the annotations about an input channel.
#[derive(Debug, Clone)]
pub struct InputChannel {
    pub id: u16,
    pub schema_id: u16,
    pub topic: String,
    pub message_encoding: String,
    /// The schema's name and text (empty for a schemaless channel): what tells whether its messages
    /// start with a `std_msgs/Header`.
    pub schema_name: String,
    pub schema_data: std::sync::Arc<[u8]>,
}

/// A message as the copy writes it, when [`Annotations::rewrite`] changes it.
pub type Rewritten = (MessageHeader, Vec<u8>);

/// Writes one input message to the copy — as [`Annotations::rewrite`] changes it, or unchanged —
/// after [`Annotations::before_message`]; returns its log time as written.
pub fn write_message<W: Write + Seek, A: Annotations<W>>(
    w: &mut Writer<W>,
    annotations: &mut A,
    part: usize,
    channel: &InputChannel,
    header: &MessageHeader,
    data: &[u8],
    output_path: &Path,
) -> Result<u64> {
    let write_err = |e: McapError| Error::Output {
        path: output_path.to_path_buf(),
        detail: e.to_string(),
    };
    annotations.before_message(w, channel, header, data)?;
    match annotations.rewrite(part, channel, header, data)? {
        Some((h, d)) => {
            w.write_to_known_channel(&h, &d).map_err(write_err)?;
            Ok(h.log_time)
        }
        None => {
            w.write_to_known_channel(header, data).map_err(write_err)?;
            Ok(header.log_time)
        }
    }
}

/// Adds records to the copy. Each hook gets the writer; ids it uses must not clash with the input's.
pub trait Annotations<W: Write + Seek> {
    /// Called once, after the input's header, before any other record.
    fn start(&mut self, writer: &mut Writer<W>) -> Result<()>;
    /// Called for every input message, before it is copied.
    fn before_message(
        &mut self,
        writer: &mut Writer<W>,
        channel: &InputChannel,
        header: &MessageHeader,
        data: &[u8],
    ) -> Result<()>;
    /// The message to write in place of the input's (its times and bytes changed): `None`, the
    /// default, copies it unchanged. `part` is the index of the file it came from within a mission
    /// ([`crate::sources::mission::Mission::parts`]; 0 for a single recording).
    fn rewrite(
        &mut self,
        part: usize,
        channel: &InputChannel,
        header: &MessageHeader,
        data: &[u8],
    ) -> Result<Option<Rewritten>> {
        let _ = (part, channel, header, data);
        Ok(None)
    }
    /// Called once after the last input record; the writer is finished by the caller.
    fn finish(&mut self, writer: &mut Writer<W>) -> Result<()>;
}

/// How the copy went.
#[derive(Debug, Clone, Default)]
pub struct CopyOutcome {
    pub messages: u64,
    pub attachments: u64,
    pub metadata: u64,
    /// Largest log time copied (0 when no message).
    pub last_log_time: u64,
    /// `Some(offset)` when the input ended early (everything before was copied).
    pub truncated_at: Option<u64>,
}

const PROGRESS_STEP: u64 = 1 << 20;

/// Copies `input` into `out` record by record, calling `annotations` along the way. `options` sets the
/// output's compression and library; the profile is taken from the input's header. Returns the sink
/// (to flush and sync).
pub fn copy_with<W: Write + Seek, A: Annotations<W>>(
    input: &Path,
    out: W,
    output_path: &Path,
    options: mcap::WriteOptions,
    annotations: &mut A,
    progress: Progress<'_>,
) -> Result<(CopyOutcome, W)> {
    let (mut file, mut reader, magic, file_size) = open_linear(input)?;

    let corrupt = |detail: String| Error::CorruptMcap {
        path: input.to_path_buf(),
        detail,
    };
    let write_err = |e: McapError| Error::Output {
        path: output_path.to_path_buf(),
        detail: e.to_string(),
    };
    let mut options = Some(options);
    let mut out = Some(out);
    let mut writer: Option<Writer<W>> = None;
    let mut channels: HashMap<u16, InputChannel> = HashMap::new();
    let mut schemas: HashMap<u16, (String, std::sync::Arc<[u8]>)> = HashMap::new();
    let mut outcome = CopyOutcome::default();
    let mut bytes_read = magic.len() as u64;
    let mut last_progress = 0;

    // The writer is created at the input's header (to keep its profile), or at the first other record
    // of a file without one.
    let mut ensure_writer =
        |writer: &mut Option<Writer<W>>, profile: &str, annotations: &mut A| -> Result<()> {
            if writer.is_none() {
                let (Some(o), Some(sink)) = (options.take(), out.take()) else {
                    return Ok(());
                };
                let mut w = o.profile(profile).create(sink).map_err(write_err)?;
                annotations.start(&mut w)?;
                *writer = Some(w);
            }
            Ok(())
        };

    while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(event) => event,
            Err(McapError::UnexpectedEof) => {
                outcome.truncated_at = Some(bytes_read);
                break;
            }
            Err(e) => {
                return Err(corrupt(format!(
                    "{e} (before byte {bytes_read} of {file_size})"
                )))
            }
        };
        let (opcode, data) = match event {
            LinearReadEvent::ReadRequest(need) => {
                let n = fill(
                    &mut reader,
                    &mut file,
                    need,
                    file_size.saturating_sub(bytes_read),
                )
                .map_err(|e| Error::io(input, e))?;
                bytes_read += n as u64;
                if bytes_read - last_progress >= PROGRESS_STEP {
                    last_progress = bytes_read;
                    progress(bytes_read);
                }
                continue;
            }
            LinearReadEvent::Record { opcode, data } => (opcode, data),
        };
        if opcode == op::DATA_END {
            break;
        }
        crate::sources::mcap::lengths::check_record(opcode, data)
            .map_err(|d| corrupt(format!("record 0x{opcode:02x}: {d}")))?;
        let record = mcap::parse_record(opcode, data)
            .map_err(|e| corrupt(format!("record 0x{opcode:02x}: {e}")))?;
        if let Record::Header(h) = &record {
            ensure_writer(&mut writer, &h.profile, annotations)?;
            continue;
        }
        ensure_writer(&mut writer, "", annotations)?;
        let Some(w) = writer.as_mut() else {
            continue;
        };
        match record {
            Record::Schema { header, data } => {
                w.add_schema_with_id(header.id, &header.name, &header.encoding, &data)
                    .map_err(write_err)?;
                schemas
                    .entry(header.id)
                    .or_insert_with(|| (header.name.clone(), data.to_vec().into()));
            }
            Record::Channel(c) => {
                w.add_channel_with_id(
                    c.id,
                    c.schema_id,
                    &c.topic,
                    &c.message_encoding,
                    &c.metadata,
                )
                .map_err(write_err)?;
                let (schema_name, schema_data) = schemas
                    .get(&c.schema_id)
                    .cloned()
                    .unwrap_or_else(|| (String::new(), std::sync::Arc::from(&[][..])));
                channels.entry(c.id).or_insert(InputChannel {
                    id: c.id,
                    schema_id: c.schema_id,
                    topic: c.topic,
                    message_encoding: c.message_encoding,
                    schema_name,
                    schema_data,
                });
            }
            Record::Message { header, data } => {
                let channel = channels.get(&header.channel_id).ok_or_else(|| {
                    corrupt(format!(
                        "message on channel {} before its channel record",
                        header.channel_id
                    ))
                })?;
                let log_time =
                    write_message(w, annotations, 0, channel, &header, &data, output_path)?;
                outcome.messages += 1;
                outcome.last_log_time = outcome.last_log_time.max(log_time);
            }
            Record::Attachment { header, data, .. } => {
                w.attach(&mcap::Attachment {
                    log_time: header.log_time,
                    create_time: header.create_time,
                    name: header.name,
                    media_type: header.media_type,
                    data,
                })
                .map_err(write_err)?;
                outcome.attachments += 1;
            }
            Record::Metadata(m) => {
                w.write_metadata(&m).map_err(write_err)?;
                outcome.metadata += 1;
            }
            // Indexes, statistics, chunk framing and summary records are rewritten by the writer.
            _ => {}
        }
    }
    progress(bytes_read);
    ensure_writer(&mut writer, "", annotations)?;
    let Some(mut w) = writer else {
        return Err(corrupt("no record could be read".into()));
    };
    annotations.finish(&mut w)?;
    w.finish().map_err(write_err)?;
    Ok((outcome, w.into_inner()))
}

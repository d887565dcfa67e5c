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
use crate::sources::mcap::lengths::read_footer;
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

/// The input side of the copy: the input's records in file order, read through the linear reader
/// (each record's lengths checked before it is parsed), with progress; a file that ends early ends
/// the stream and says where.
struct RecordStream<'a> {
    input: &'a Path,
    file: std::fs::File,
    reader: mcap::sans_io::LinearReader,
    file_size: u64,
    bytes_read: u64,
    last_progress: u64,
    progress: Progress<'a>,
    /// `Some(offset)` once the input ended early.
    truncated_at: Option<u64>,
}

impl<'a> RecordStream<'a> {
    fn open(input: &'a Path, progress: Progress<'a>) -> Result<RecordStream<'a>> {
        let (file, reader, magic, file_size) = open_linear(input)?;
        Ok(RecordStream {
            input,
            file,
            reader,
            file_size,
            bytes_read: magic.len() as u64,
            last_progress: 0,
            progress,
            truncated_at: None,
        })
    }

    fn corrupt(&self, detail: String) -> Error {
        Error::CorruptMcap {
            path: self.input.to_path_buf(),
            detail,
        }
    }

    /// Calls `each` with every record up to the data's end (or where a truncated file ends).
    fn for_each(&mut self, mut each: impl FnMut(Record<'_>) -> Result<()>) -> Result<()> {
        while let Some(event) = self.reader.next_event() {
            let (opcode, data) = match event {
                Ok(LinearReadEvent::ReadRequest(need)) => {
                    let left = self.file_size.saturating_sub(self.bytes_read);
                    let n = fill(&mut self.reader, &mut self.file, need, left)
                        .map_err(|e| Error::io(self.input, e))?;
                    self.bytes_read += n as u64;
                    if self.bytes_read - self.last_progress >= PROGRESS_STEP {
                        self.last_progress = self.bytes_read;
                        (self.progress)(self.bytes_read);
                    }
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) => (opcode, data),
                Err(McapError::UnexpectedEof) => {
                    self.truncated_at = Some(self.bytes_read);
                    return Ok(());
                }
                Err(e) => {
                    let detail = format!(
                        "{e} (before byte {} of {})",
                        self.bytes_read, self.file_size
                    );
                    return Err(self.corrupt(detail));
                }
            };
            if opcode == op::DATA_END {
                // Whole data, but no footer and end magic after it: still a file cut short.
                if read_footer(&mut self.file, self.file_size)
                    .map_err(|e| Error::io(self.input, e))?
                    .is_none()
                {
                    self.truncated_at = Some(self.file_size);
                }
                return Ok(());
            }
            let corrupt = |detail: String| Error::CorruptMcap {
                path: self.input.to_path_buf(),
                detail: format!("record 0x{opcode:02x}: {detail}"),
            };
            crate::sources::mcap::lengths::check_record(opcode, data)
                .map_err(|d| corrupt(d.to_string()))?;
            each(mcap::parse_record(opcode, data).map_err(|e| corrupt(e.to_string()))?)?;
        }
        Ok(())
    }
}

/// The output side of the copy: the writer (created at the input's header, to keep its profile, or
/// at the first other record of a file without one), the input's channels and schemas as they are
/// declared, and what was copied.
struct RecordCopier<'a, W: Write + Seek> {
    input: &'a Path,
    output_path: &'a Path,
    options: Option<mcap::WriteOptions>,
    out: Option<W>,
    writer: Option<Writer<W>>,
    channels: HashMap<u16, InputChannel>,
    schemas: HashMap<u16, (String, std::sync::Arc<[u8]>)>,
    outcome: CopyOutcome,
}

impl<W: Write + Seek> RecordCopier<'_, W> {
    fn write_err(&self, e: McapError) -> Error {
        Error::Output {
            path: self.output_path.to_path_buf(),
            detail: e.to_string(),
        }
    }

    /// Creates the writer with `profile` unless it exists.
    fn ensure_writer<A: Annotations<W>>(
        &mut self,
        profile: &str,
        annotations: &mut A,
    ) -> Result<()> {
        if self.writer.is_none() {
            let (Some(o), Some(sink)) = (self.options.take(), self.out.take()) else {
                return Ok(());
            };
            let mut w = o
                .profile(profile)
                .create(sink)
                .map_err(|e| self.write_err(e))?;
            annotations.start(&mut w)?;
            self.writer = Some(w);
        }
        Ok(())
    }

    /// Copies one record: schemas, channels, messages (through the annotations), attachments and
    /// metadata; indexes, statistics, chunk framing and summary records are rewritten by the writer.
    fn copy<A: Annotations<W>>(&mut self, record: Record<'_>, annotations: &mut A) -> Result<()> {
        if let Record::Header(h) = &record {
            return self.ensure_writer(&h.profile, annotations);
        }
        self.ensure_writer("", annotations)?;
        let output_path = self.output_path;
        let write_err = |e: McapError| Error::Output {
            path: output_path.to_path_buf(),
            detail: e.to_string(),
        };
        let Some(w) = self.writer.as_mut() else {
            return Ok(());
        };
        match record {
            Record::Schema { header, data } => {
                w.add_schema_with_id(header.id, &header.name, &header.encoding, &data)
                    .map_err(write_err)?;
                self.schemas
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
                let (schema_name, schema_data) = self
                    .schemas
                    .get(&c.schema_id)
                    .cloned()
                    .unwrap_or_else(|| (String::new(), std::sync::Arc::from(&[][..])));
                self.channels.entry(c.id).or_insert(InputChannel {
                    id: c.id,
                    schema_id: c.schema_id,
                    topic: c.topic,
                    message_encoding: c.message_encoding,
                    schema_name,
                    schema_data,
                });
            }
            Record::Message { header, data } => {
                let channel =
                    self.channels
                        .get(&header.channel_id)
                        .ok_or_else(|| Error::CorruptMcap {
                            path: self.input.to_path_buf(),
                            detail: format!(
                                "message on channel {} before its channel record",
                                header.channel_id
                            ),
                        })?;
                let log_time =
                    write_message(w, annotations, 0, channel, &header, &data, output_path)?;
                self.outcome.messages += 1;
                self.outcome.last_log_time = self.outcome.last_log_time.max(log_time);
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
                self.outcome.attachments += 1;
            }
            Record::Metadata(m) => {
                w.write_metadata(&m).map_err(write_err)?;
                self.outcome.metadata += 1;
            }
            _ => {}
        }
        Ok(())
    }
}

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
    let mut records = RecordStream::open(input, progress)?;
    let mut copier = RecordCopier {
        input,
        output_path,
        options: Some(options),
        out: Some(out),
        writer: None,
        channels: HashMap::new(),
        schemas: HashMap::new(),
        outcome: CopyOutcome::default(),
    };
    records.for_each(|record| copier.copy(record, annotations))?;
    copier.outcome.truncated_at = records.truncated_at;
    (records.progress)(records.bytes_read);
    copier.ensure_writer("", annotations)?;
    let Some(mut w) = copier.writer.take() else {
        return Err(records.corrupt("no record could be read".into()));
    };
    annotations.finish(&mut w)?;
    w.finish().map_err(|e| copier.write_err(e))?;
    Ok((copier.outcome, w.into_inner()))
}

//! The one streaming pass over an MCAP file that every read builds on.
//!
//! `mcap::sans_io::LinearReader` walks the records in file order, decompressing zstd/lz4 chunks a piece
//! at a time, so memory follows the largest record, not the file. We keep only channel and schema
//! names; a message on a channel nobody asked for is recognised by its first two bytes (the channel
//! id) and dropped without being parsed or copied. The pass stops at the Data End record (the summary
//! after it only repeats what was read). A file that ends early (a recorder that crashed: no Data End,
//! no footer, a chunk cut in half) yields every record before the cut and reports where it was cut.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use super::lengths::{check_record, read_footer};
use mcap::records::{op, Record};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::McapError;

use crate::error::{Error, Result};
use crate::sources::recording::{ChannelInfo, MessageRef, StreamOutcome};
use crate::sources::Progress;

/// How many bytes to ask the OS for at least per read: fewer syscalls than the reader's
/// per-record requests (a buffered reader would copy the bytes twice).
const MIN_READ: usize = 256 * 1024;

/// Progress is reported at most once per this many bytes.
const PROGRESS_STEP: u64 = 1 << 20;

/// Reads `path` once, in file order. `select` is asked once per channel (at its first record) whether
/// its messages are wanted; `on_message` gets every message of a selected channel. Returns what was
/// learned about all channels. A truncated file is not an error (see [`StreamOutcome::truncated_at`]);
/// damage elsewhere is [`Error::CorruptMcap`], a bad magic [`Error::NotMcap`], an error returned by
/// `on_message` stops the pass and is returned as is.
///
/// This loop answers the reader's requests for bytes and routes each record by its opcode to
/// `Pass`, which keeps what the records taught.
pub fn for_each_message<S, F>(
    path: &Path,
    mut select: S,
    progress: Progress<'_>,
    mut on_message: F,
) -> Result<StreamOutcome>
where
    S: FnMut(&ChannelInfo) -> bool,
    F: FnMut(&ChannelInfo, &MessageRef<'_>) -> Result<()>,
{
    let (mut file, mut reader, magic, file_size) = open_linear(path)?;
    let mut pass = Pass {
        path,
        schemas: HashMap::new(),
        channels: HashMap::new(),
        out: StreamOutcome {
            bytes_read: magic.len() as u64,
            ..Default::default()
        },
    };
    let mut last_progress = 0u64;
    while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(event) => event,
            Err(McapError::UnexpectedEof) => {
                pass.out.truncated_at = Some(pass.out.bytes_read);
                break;
            }
            Err(e) => {
                return Err(pass.corrupt(format!(
                    "{e} (before byte {} of {file_size})",
                    pass.out.bytes_read
                )))
            }
        };
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let n = fill(
                    &mut reader,
                    &mut file,
                    need,
                    file_size.saturating_sub(pass.out.bytes_read),
                )
                .map_err(|e| Error::io(path, e))?;
                pass.out.bytes_read += n as u64;
                if pass.out.bytes_read - last_progress >= PROGRESS_STEP {
                    last_progress = pass.out.bytes_read;
                    progress(pass.out.bytes_read);
                }
            }
            LinearReadEvent::Record { opcode, data } => match opcode {
                op::MESSAGE => pass.message(data, &mut on_message)?,
                op::SCHEMA => pass.schema(data)?,
                op::CHANNEL => pass.channel(data, &mut select)?,
                op::DATA_END => {
                    // The data is whole, but a file without its footer and end magic was still cut
                    // short (the summary after the data, or its last bytes, are missing).
                    if read_footer(&mut file, file_size)
                        .map_err(|e| Error::io(path, e))?
                        .is_none()
                    {
                        pass.out.truncated_at = Some(file_size);
                    }
                    break;
                }
                _ => {}
            },
        }
    }
    progress(pass.out.bytes_read);
    Ok(pass.out)
}

/// What one pass has learned: schema and channel names, which channels are selected, and the
/// outcome so far (channels, message counts, bytes read).
struct Pass<'p> {
    path: &'p Path,
    /// Schema id → (name, encoding, data).
    schemas: HashMap<u16, (String, String, std::sync::Arc<[u8]>)>,
    /// Channel id → (index into `out.channels`, selected).
    channels: HashMap<u16, (usize, bool)>,
    out: StreamOutcome,
}

impl Pass<'_> {
    /// Damage in the file, as its one-line error.
    #[cold]
    fn corrupt(&self, detail: String) -> Error {
        Error::CorruptMcap {
            path: self.path.to_path_buf(),
            detail,
        }
    }

    /// A message record: counted, then handed to `on_message` when its channel is selected. The
    /// channel id is the first field: unselected messages are skipped unparsed (the hot path of a
    /// recording whose bulk is images and scans).
    #[inline]
    fn message<F>(&mut self, data: &[u8], on_message: &mut F) -> Result<()>
    where
        F: FnMut(&ChannelInfo, &MessageRef<'_>) -> Result<()>,
    {
        let Some(id) = data.get(..2).map(|b| u16::from_le_bytes([b[0], b[1]])) else {
            return Err(self.corrupt(format!(
                "message record of {} bytes (before byte {})",
                data.len(),
                self.out.bytes_read
            )));
        };
        *self.out.message_counts.entry(id).or_default() += 1;
        let Some(&(index, true)) = self.channels.get(&id) else {
            return Ok(());
        };
        let Record::Message { header, data } = mcap::parse_record(op::MESSAGE, data)
            .map_err(|e| self.corrupt(format!("message record: {e}")))?
        else {
            return Ok(());
        };
        let message = MessageRef {
            channel_id: header.channel_id,
            sequence: header.sequence,
            log_time: header.log_time,
            publish_time: header.publish_time,
            data: &data,
        };
        on_message(&self.out.channels[index], &message)
    }

    /// A schema record: its name, encoding and text kept for the channels that name it (the first
    /// record of an id wins).
    fn schema(&mut self, data: &[u8]) -> Result<()> {
        check_record(op::SCHEMA, data).map_err(|d| {
            self.corrupt(format!(
                "schema record before byte {}: {d}",
                self.out.bytes_read
            ))
        })?;
        if let Ok(Record::Schema { header, data }) = mcap::parse_record(op::SCHEMA, data) {
            self.schemas.entry(header.id).or_insert((
                header.name,
                header.encoding,
                data.as_ref().into(),
            ));
        }
        Ok(())
    }

    /// A channel record: the channel (with its schema) added to the outcome at its first record, and
    /// `select` asked once whether its messages are wanted.
    fn channel<S>(&mut self, data: &[u8], select: &mut S) -> Result<()>
    where
        S: FnMut(&ChannelInfo) -> bool,
    {
        check_record(op::CHANNEL, data).map_err(|d| {
            self.corrupt(format!(
                "channel record before byte {}: {d}",
                self.out.bytes_read
            ))
        })?;
        let Record::Channel(c) = mcap::parse_record(op::CHANNEL, data)
            .map_err(|e| self.corrupt(format!("channel record: {e}")))?
        else {
            return Ok(());
        };
        if self.channels.contains_key(&c.id) {
            return Ok(());
        }
        let (schema_name, schema_encoding, schema_data) =
            self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
        let info = ChannelInfo {
            id: c.id,
            topic: c.topic,
            schema_name,
            schema_encoding,
            message_encoding: c.message_encoding,
            schema_data,
        };
        let selected = select(&info);
        self.channels
            .insert(info.id, (self.out.channels.len(), selected));
        self.out.channels.push(info);
        Ok(())
    }
}

/// Opens `path` and a [`LinearReader`] over it that has already consumed the magic: the one way every
/// streaming pass (extraction, topics, the annotated copy) starts. Chunk CRCs are checked; a record cannot
/// be longer than the file, except one inside a compressed chunk, so the length limit keeps a corrupt
/// length from allocating gigabytes before the read fails. Returns the file, the reader, the magic and the file's size.
pub fn open_linear(path: &Path) -> Result<(std::fs::File, LinearReader, [u8; 8], u64)> {
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let file_size = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let magic = read_magic(&mut file, path)?;
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_validate_chunk_crcs(true)
            .with_record_length_limit(record_length_limit(file_size)),
    );
    reader.insert(magic.len()).copy_from_slice(&magic);
    reader.notify_read(magic.len());
    Ok((file, reader, magic, file_size))
}

/// The longest record the reader accepts in a file of `file_size` bytes. A record in the file cannot be
/// longer than the file; one inside a compressed chunk can, by the compression ratio, and the crate
/// reserves (zero-fills) a declared inner length before decompressing it. So the limit is 256× the file
/// (a ratio real recordings do not reach), at least 16 MiB and at most max(256 MiB, the file): a damaged
/// length in a 3 KB file then costs 16 MiB, not 256 MiB.
fn record_length_limit(file_size: u64) -> usize {
    let limit = file_size
        .saturating_mul(256)
        .min(file_size.max(256 << 20))
        .max(16 << 20);
    usize::try_from(limit).unwrap_or(usize::MAX)
}

/// Answers the reader's request for `need` more bytes with one read of at least `MIN_READ` bytes,
/// but never more than the `left` bytes the file still holds (+1 to see its end): the reader's buffer
/// is zero-filled to the requested size, so a damaged length must not size it. Returns the bytes read
/// (0 at the end of the file).
pub fn fill(
    reader: &mut LinearReader,
    file: &mut std::fs::File,
    need: usize,
    left: u64,
) -> std::io::Result<usize> {
    let want = need.max(MIN_READ).min(
        usize::try_from(left)
            .unwrap_or(usize::MAX)
            .saturating_add(1),
    );
    let n = read_retrying(file, reader.insert(want))?;
    reader.notify_read(n);
    Ok(n)
}

/// Reads the first 8 bytes and checks they are the MCAP magic: [`Error::NotMcap`] otherwise.
pub(crate) fn read_magic(file: &mut std::fs::File, path: &Path) -> Result<[u8; 8]> {
    let mut magic = [0u8; 8];
    let mut got = 0;
    while got < magic.len() {
        match read_retrying(file, &mut magic[got..]).map_err(|e| Error::io(path, e))? {
            0 => break,
            n => got += n,
        }
    }
    if got < magic.len() || magic[..] != *mcap::MAGIC {
        return Err(Error::NotMcap {
            path: path.to_path_buf(),
            detail: if got == 0 {
                "the file is empty (0 bytes)".into()
            } else if got < magic.len() {
                format!("{got} bytes, shorter than the 8-byte magic")
            } else {
                "the file does not start with the MCAP magic".into()
            },
        });
    }
    Ok(magic)
}

/// `Read::read`, retried when interrupted by a signal.
fn read_retrying(file: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    loop {
        match file.read(buf) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            other => return other,
        }
    }
}

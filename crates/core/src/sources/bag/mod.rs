//! ROS 1 bags (format 2.0; chunks uncompressed, bz2 or lz4) as a `Source`.
//!
//! `records` reads the record layer; this file streams chunks in file order, turns connections
//! into channels (`ros1` messages, `ros1msg` schemas) and hands messages to the shared extraction
//! (`crate::sources::extract`). [`writer`] writes small bags for tests and benchmarks.

pub(crate) mod records;
pub mod writer;

use std::collections::HashMap;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::sources::recording::{
    ChannelInfo, MessageRef, OnMessage, Recording, Select, StreamOutcome,
};
use crate::sources::Progress;

use records::{op, Fields, Next, MAGIC};

/// Progress is reported at most once per this many bytes.
const PROGRESS_STEP: u64 = 1 << 20;
/// Read buffer of the file.
const BUFFER: usize = 256 * 1024;

/// A ROS 1 bag on disk. Opening checks the magic and reads the bag header record.
#[derive(Debug, Clone)]
pub struct BagSource {
    path: PathBuf,
    size: u64,
    /// Where the index (connections, chunk infos) starts; 0 for a bag that was never closed.
    index_pos: u64,
    /// The index's connections, read once (the fail-fast topic check and the evaluation's look at
    /// the reference's type both ask).
    channels: std::sync::OnceLock<Option<Vec<ChannelInfo>>>,
}

/// Channels of a pass: connection id → channel index and whether it is selected.
struct Connections {
    by_conn: HashMap<u32, (usize, bool)>,
}

impl BagSource {
    /// Opens `path`: [`Error::Io`] when it cannot be read, [`Error::CorruptBag`] when it is not a
    /// version 2.0 bag.
    pub fn open(path: &Path) -> Result<BagSource> {
        let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let size = file.metadata().map_err(|e| Error::io(path, e))?.len();
        let mut magic = [0u8; 13];
        let n = records::read_full(&mut file, &mut magic).map_err(|e| Error::io(path, e))?;
        if n < 13 || &magic != MAGIC {
            return Err(Error::CorruptBag {
                path: path.to_path_buf(),
                detail: format!(
                    "starts with {:?}, not `#ROSBAG V2.0` (ROS 1 bags of version 1.2 are not supported)",
                    String::from_utf8_lossy(&magic[..n]).trim_end()
                ),
            });
        }
        let mut header = Vec::new();
        let mut r = BufReader::new(file);
        let remaining = size.saturating_sub(MAGIC.len() as u64);
        let index_pos = match records::read_record(&mut r, &mut header, path, remaining)? {
            Next::Record { .. } => {
                let f = Fields::parse(&header).map_err(|d| corrupt(path, d))?;
                if f.op() != Some(op::BAG_HEADER) {
                    return Err(corrupt(path, "first record is not the bag header".into()));
                }
                f.u64("index_pos").unwrap_or(0)
            }
            _ => 0,
        };
        Ok(BagSource {
            path: path.to_path_buf(),
            size,
            index_pos: if index_pos >= size { 0 } else { index_pos },
            channels: std::sync::OnceLock::new(),
        })
    }

    /// The channels and per-channel message counts from the index, when the bag has one.
    fn read_index(&self) -> Option<(Vec<ChannelInfo>, HashMap<u16, u64>)> {
        if self.index_pos == 0 {
            return None;
        }
        let mut file = std::fs::File::open(&self.path).ok()?;
        file.seek(SeekFrom::Start(self.index_pos)).ok()?;
        let mut r = BufReader::new(file);
        let mut channels: Vec<ChannelInfo> = Vec::new();
        let mut conns = HashMap::new();
        let mut counts: HashMap<u32, u64> = HashMap::new();
        let (mut header, mut data) = (Vec::new(), Vec::new());
        let mut pos = self.index_pos;
        // An index cut short (the file ends inside it) lists only some of the chunks: no index then,
        // and the pass counts what the readers read.
        loop {
            let data_len = match records::read_record(
                &mut r,
                &mut header,
                &self.path,
                self.size.saturating_sub(pos),
            )
            .ok()?
            {
                Next::Record { data_len } => data_len,
                Next::End => break,
                Next::Truncated => return None,
            };
            pos += 8 + header.len() as u64 + data_len as u64;
            data.resize(data_len as usize, 0);
            r.read_exact(&mut data).ok()?;
            let f = Fields::parse(&header).ok()?;
            match f.op() {
                Some(op::CONNECTION) => {
                    let conn = f.u32("conn")?;
                    if let std::collections::hash_map::Entry::Vacant(e) = conns.entry(conn) {
                        let c = connection(&f, &data, channels.len()).ok()?;
                        e.insert(c.id);
                        channels.push(c);
                    }
                }
                Some(op::CHUNK_INFO) => {
                    let mut d = data.as_slice();
                    while d.len() >= 8 {
                        let conn = records::read_u32_slice(&mut d).ok()?;
                        let n = records::read_u32_slice(&mut d).ok()?;
                        *counts.entry(conn).or_default() += n as u64;
                    }
                }
                _ => {}
            }
        }
        let counts = counts
            .into_iter()
            .filter_map(|(conn, n)| Some((*conns.get(&conn)?, n)))
            .collect();
        Some((channels, counts))
    }

    /// The records of the chunk record at byte `record_start` (header `f`, body `data`), decompressed
    /// into `chunk` (reused from chunk to chunk): an unknown compression is its own error, a chunk
    /// that does not decompress or split into records is damage.
    fn open_chunk<'c>(
        &self,
        f: &Fields<'_>,
        data: &[u8],
        record_start: u64,
        chunk: &'c mut Vec<u8>,
    ) -> Result<Vec<(Fields<'c>, &'c [u8])>> {
        let path = &self.path;
        let compression = f.get("compression").unwrap_or(b"none");
        if !matches!(compression, b"none" | b"bz2" | b"lz4") {
            return Err(Error::UnsupportedCompression {
                path: path.clone(),
                offset: record_start,
                compression: String::from_utf8_lossy(compression).into_owned(),
            });
        }
        let size = f.u32("size").unwrap_or(0) as usize;
        decompress(compression, data, size, chunk)
            .map_err(|e| corrupt(path, format!("chunk at byte {record_start}: {e}")))?;
        records::split_records(chunk)
            .map_err(|d| corrupt(path, format!("chunk at byte {record_start}: {d}")))
    }

    /// Hands every record of a chunk (or a top-level record) to connection/message handling.
    #[allow(clippy::too_many_arguments)]
    fn handle(
        &self,
        f: &Fields<'_>,
        data: &[u8],
        conns: &mut Connections,
        out: &mut StreamOutcome,
        select: &mut Select<'_>,
        on_message: &mut OnMessage<'_>,
    ) -> Result<()> {
        match f.op() {
            Some(op::CONNECTION) => {
                let conn = f
                    .u32("conn")
                    .ok_or_else(|| corrupt(&self.path, "connection without `conn`".into()))?;
                if let std::collections::hash_map::Entry::Vacant(e) = conns.by_conn.entry(conn) {
                    let c = connection(f, data, out.channels.len())
                        .map_err(|d| corrupt(&self.path, d))?;
                    let selected = select(&c);
                    e.insert((out.channels.len(), selected));
                    out.channels.push(c);
                }
            }
            Some(op::MESSAGE_DATA) => {
                let conn = f
                    .u32("conn")
                    .ok_or_else(|| corrupt(&self.path, "message without `conn`".into()))?;
                let Some(&(i, selected)) = conns.by_conn.get(&conn) else {
                    return Err(corrupt(
                        &self.path,
                        format!("message on connection {conn} before its connection record"),
                    ));
                };
                let c = &out.channels[i];
                *out.message_counts.entry(c.id).or_default() += 1;
                if selected {
                    let log_time = f.time_ns("time").unwrap_or(0);
                    on_message(
                        c,
                        &MessageRef {
                            channel_id: c.id,
                            sequence: 0,
                            log_time,
                            publish_time: log_time,
                            data,
                        },
                    )?;
                }
            }
            _ => {}
        }
        Ok(())
    }
}

fn corrupt(path: &Path, detail: String) -> Error {
    Error::CorruptBag {
        path: path.to_path_buf(),
        detail,
    }
}

/// A channel from a connection record (`data` holds the connection header: topic, type, ...).
fn connection(
    f: &Fields<'_>,
    data: &[u8],
    index: usize,
) -> std::result::Result<ChannelInfo, String> {
    let id = u16::try_from(index).map_err(|_| "more than 65536 connections".to_string())?;
    let d = Fields::parse(data)?;
    Ok(ChannelInfo {
        id,
        topic: f
            .text("topic")
            .or_else(|| d.text("topic"))
            .ok_or("connection without topic")?,
        schema_name: d.text("type").unwrap_or_default(),
        schema_encoding: "ros1msg".into(),
        message_encoding: "ros1".into(),
        schema_data: d.get("message_definition").unwrap_or_default().into(),
    })
}

/// The largest chunk trajdrift decompresses (rosbag's default chunk is 768 KiB).
const MAX_CHUNK: usize = 256 << 20;

/// Decompresses a chunk's data into `out`: never more than the `size` the chunk header declares (a
/// compressed bomb or a damaged stream stops there), and a declared size over [`MAX_CHUNK`] is damage.
fn decompress(
    compression: &[u8],
    data: &[u8],
    size: usize,
    out: &mut Vec<u8>,
) -> std::io::Result<()> {
    use std::io::{Error as IoError, ErrorKind};
    out.clear();
    if size > MAX_CHUNK {
        return Err(IoError::new(
            ErrorKind::InvalidData,
            format!("declares {size} bytes uncompressed, more than {MAX_CHUNK}"),
        ));
    }
    out.reserve(size);
    let limit = size as u64 + 1;
    match compression {
        b"bz2" => bzip2::read::BzDecoder::new(data)
            .take(limit)
            .read_to_end(out)
            .map(|_| ()),
        b"lz4" => lz4_flex::frame::FrameDecoder::new(data)
            .take(limit)
            .read_to_end(out)
            .map(|_| ()),
        _ => {
            out.extend_from_slice(data);
            Ok(())
        }
    }?;
    if out.len() > size && compression != b"none" {
        return Err(IoError::new(
            ErrorKind::InvalidData,
            format!("decompresses to more than the {size} bytes it declares"),
        ));
    }
    Ok(())
}

impl Recording for BagSource {
    fn recording_size(&self) -> u64 {
        self.size
    }

    fn channel_counts(&self) -> Result<(Vec<ChannelInfo>, HashMap<u16, u64>)> {
        Ok(match self.read_index() {
            Some(x) => x,
            None => {
                let o = self.pass(&mut |_| false, &|_| {}, &mut |_, _| Ok(()))?;
                (o.channels, o.message_counts)
            }
        })
    }

    fn path(&self) -> &Path {
        &self.path
    }

    fn known_channels(&self) -> Option<Vec<ChannelInfo>> {
        self.channels
            .get_or_init(|| self.read_index().map(|(c, _)| c))
            .clone()
    }

    fn pass(
        &self,
        mut select: Select<'_>,
        progress: Progress<'_>,
        mut on_message: OnMessage<'_>,
    ) -> Result<StreamOutcome> {
        let path = &self.path;
        let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        file.seek(SeekFrom::Start(MAGIC.len() as u64))
            .map_err(|e| Error::io(path, e))?;
        let mut r = BufReader::with_capacity(BUFFER, file);
        let mut out = StreamOutcome::default();
        let mut conns = Connections {
            by_conn: HashMap::new(),
        };
        let (mut header, mut data, mut chunk) = (Vec::new(), Vec::new(), Vec::new());
        let mut pos = MAGIC.len() as u64;
        let mut last_progress = 0;
        loop {
            // Read up to the end of the file, not to `index_pos`: the index only repeats connections
            // (already seen ones are skipped), and a damaged `index_pos` must not hide the data.
            let data_len = match records::read_record(
                &mut r,
                &mut header,
                path,
                self.size.saturating_sub(pos),
            )? {
                Next::End => break,
                Next::Truncated => {
                    out.truncated_at = Some(pos);
                    break;
                }
                Next::Record { data_len } => data_len,
            };
            let record_start = pos;
            pos += 8 + header.len() as u64 + data_len as u64;
            let f = Fields::parse(&header)
                .map_err(|d| corrupt(path, format!("record header at byte {record_start}: {d}")))?;
            let wanted = matches!(
                f.op(),
                Some(op::CHUNK) | Some(op::CONNECTION) | Some(op::MESSAGE_DATA)
            );
            if !wanted {
                r.seek_relative(data_len as i64)
                    .map_err(|e| Error::io(path, e))?;
                continue;
            }
            data.resize(data_len as usize, 0);
            let n = records::read_full(&mut r, &mut data).map_err(|e| Error::io(path, e))?;
            if n < data.len() {
                out.truncated_at = Some(record_start);
                break;
            }
            if f.op() == Some(op::CHUNK) {
                let inner = self.open_chunk(&f, &data, record_start, &mut chunk)?;
                for (f, d) in &inner {
                    self.handle(f, d, &mut conns, &mut out, &mut select, &mut on_message)?;
                }
            } else {
                self.handle(
                    &f,
                    &data,
                    &mut conns,
                    &mut out,
                    &mut select,
                    &mut on_message,
                )?;
            }
            if pos - last_progress >= PROGRESS_STEP {
                last_progress = pos;
                progress(pos);
            }
        }
        out.bytes_read = pos;
        Ok(out)
    }
}

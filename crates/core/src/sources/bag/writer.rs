//! A small ROS 1 bag v2.0 writer, for tests and benchmarks (bags of any size and compression,
//! written by our own code).
//!
//! It writes the bag header, chunks (each carrying the connection records of the connections first
//! used in it, then message data records), after each chunk its index data records (op 0x04: per
//! connection, each message's time and offset in the chunk, which `rosbag` and `rosbags` read;
//! trajdrift itself reads in file order and skips them) and the index (connections, chunk infos with
//! per-connection counts).

use std::collections::BTreeMap;
use std::io::{Seek, SeekFrom, Write};

use super::records::{op, MAGIC};

/// Chunk compression (`compression` field). `Other` writes an arbitrary name, uncompressed, to
/// test readers against unknown compressions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BagCompression {
    None,
    Bz2,
    Lz4,
    Other(String),
}

/// A bag being written.
pub struct BagWriter<W: Write + Seek> {
    out: W,
    compression: BagCompression,
    chunk_target: usize,
    /// Connection id → (topic, type, message definition, md5sum).
    connections: Vec<(String, String, String, String)>,
    /// Connections whose record is already in some chunk... and in the current one.
    in_chunk: Vec<bool>,
    chunk: Vec<u8>,
    chunk_counts: BTreeMap<u32, u32>,
    /// Per connection, (time, offset in the uncompressed chunk) of the current chunk's messages.
    chunk_index: BTreeMap<u32, Vec<(u64, u32)>>,
    chunk_times: Option<(u64, u64)>,
    /// (chunk position, start, end, counts) for the index.
    chunk_infos: Vec<(u64, u64, u64, BTreeMap<u32, u32>)>,
}

fn field(name: &str, value: &[u8]) -> Vec<u8> {
    let mut f = ((name.len() + 1 + value.len()) as u32)
        .to_le_bytes()
        .to_vec();
    f.extend_from_slice(name.as_bytes());
    f.push(b'=');
    f.extend_from_slice(value);
    f
}

fn time(ns: u64) -> [u8; 8] {
    let mut t = [0u8; 8];
    t[..4].copy_from_slice(&((ns / 1_000_000_000) as u32).to_le_bytes());
    t[4..].copy_from_slice(&((ns % 1_000_000_000) as u32).to_le_bytes());
    t
}

fn record(out: &mut Vec<u8>, header: &[Vec<u8>], data: &[u8]) {
    let h: Vec<u8> = header.concat();
    out.extend_from_slice(&(h.len() as u32).to_le_bytes());
    out.extend_from_slice(&h);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(data);
}

impl<W: Write + Seek> BagWriter<W> {
    /// Starts a bag in `out` with chunks of about `chunk_target` bytes (rosbag's default: 768 KiB).
    pub fn new(
        mut out: W,
        compression: BagCompression,
        chunk_target: usize,
    ) -> std::io::Result<Self> {
        out.write_all(MAGIC)?;
        let mut w = BagWriter {
            out,
            compression,
            chunk_target,
            connections: Vec::new(),
            in_chunk: Vec::new(),
            chunk: Vec::new(),
            chunk_counts: BTreeMap::new(),
            chunk_index: BTreeMap::new(),
            chunk_times: None,
            chunk_infos: Vec::new(),
        };
        w.write_bag_header(0)?;
        Ok(w)
    }

    fn write_bag_header(&mut self, index_pos: u64) -> std::io::Result<()> {
        let header = [
            field("op", &[op::BAG_HEADER]),
            field("index_pos", &index_pos.to_le_bytes()),
            field("conn_count", &(self.connections.len() as u32).to_le_bytes()),
            field(
                "chunk_count",
                &(self.chunk_infos.len() as u32).to_le_bytes(),
            ),
        ];
        let hlen: usize = header.iter().map(Vec::len).sum();
        // The bag header record is padded to 4096 bytes so it can be rewritten in place.
        let mut rec = Vec::new();
        record(&mut rec, &header, &vec![b' '; 4096 - 8 - hlen]);
        self.out.write_all(&rec)
    }

    /// Adds a connection without a message definition; returns its id.
    pub fn add_connection(&mut self, topic: &str, type_name: &str) -> u32 {
        self.add_connection_with_definition(topic, type_name, "", "*")
    }

    /// Adds a connection with its `message_definition` (the `gendeps --cat` text readers such as
    /// `mcap-ros1-support` decode with) and `md5sum` (which `rosbag` and `rosbags` check); returns
    /// its id.
    pub fn add_connection_with_definition(
        &mut self,
        topic: &str,
        type_name: &str,
        definition: &str,
        md5sum: &str,
    ) -> u32 {
        self.connections.push((
            topic.into(),
            type_name.into(),
            definition.into(),
            md5sum.into(),
        ));
        self.in_chunk.push(false);
        (self.connections.len() - 1) as u32
    }

    fn connection_record(&self, out: &mut Vec<u8>, conn: u32) {
        let (topic, ty, definition, md5sum) = &self.connections[conn as usize];
        let data = [
            field("topic", topic.as_bytes()),
            field("type", ty.as_bytes()),
            field("md5sum", md5sum.as_bytes()),
            field("message_definition", definition.as_bytes()),
        ]
        .concat();
        record(
            out,
            &[
                field("op", &[op::CONNECTION]),
                field("conn", &conn.to_le_bytes()),
                field("topic", topic.as_bytes()),
            ],
            &data,
        );
    }

    /// Writes one message (ROS 1 serialized) received at `time_ns`.
    pub fn write(&mut self, conn: u32, time_ns: u64, data: &[u8]) -> std::io::Result<()> {
        if !self.in_chunk[conn as usize] {
            self.in_chunk[conn as usize] = true;
            let mut c = std::mem::take(&mut self.chunk);
            self.connection_record(&mut c, conn);
            self.chunk = c;
        }
        self.chunk_index
            .entry(conn)
            .or_default()
            .push((time_ns, self.chunk.len() as u32));
        record(
            &mut self.chunk,
            &[
                field("op", &[op::MESSAGE_DATA]),
                field("conn", &conn.to_le_bytes()),
                field("time", &time(time_ns)),
            ],
            data,
        );
        *self.chunk_counts.entry(conn).or_default() += 1;
        let (s, e) = self.chunk_times.unwrap_or((time_ns, time_ns));
        self.chunk_times = Some((s.min(time_ns), e.max(time_ns)));
        if self.chunk.len() >= self.chunk_target {
            self.flush_chunk()?;
        }
        Ok(())
    }

    fn flush_chunk(&mut self) -> std::io::Result<()> {
        if self.chunk.is_empty() {
            return Ok(());
        }
        let (name, data): (&[u8], Vec<u8>) = match &self.compression {
            BagCompression::None => (b"none", self.chunk.clone()),
            BagCompression::Bz2 => {
                let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::fast());
                e.write_all(&self.chunk)?;
                (b"bz2", e.finish()?)
            }
            BagCompression::Lz4 => {
                let mut e = lz4_flex::frame::FrameEncoder::new(Vec::new());
                e.write_all(&self.chunk)?;
                (b"lz4", e.finish().map_err(std::io::Error::other)?)
            }
            BagCompression::Other(n) => (n.as_bytes(), self.chunk.clone()),
        };
        let pos = self.out.stream_position()?;
        let mut rec = Vec::new();
        record(
            &mut rec,
            &[
                field("op", &[op::CHUNK]),
                field("compression", name),
                field("size", &(self.chunk.len() as u32).to_le_bytes()),
            ],
            &data,
        );
        for (conn, entries) in std::mem::take(&mut self.chunk_index) {
            let data: Vec<u8> = entries
                .iter()
                .flat_map(|&(t, offset)| [&time(t)[..], &offset.to_le_bytes()[..]].concat())
                .collect();
            record(
                &mut rec,
                &[
                    field("op", &[op::INDEX_DATA]),
                    field("ver", &1u32.to_le_bytes()),
                    field("conn", &conn.to_le_bytes()),
                    field("count", &(entries.len() as u32).to_le_bytes()),
                ],
                &data,
            );
        }
        self.out.write_all(&rec)?;
        let (s, e) = self.chunk_times.take().unwrap_or((0, 0));
        self.chunk_infos
            .push((pos, s, e, std::mem::take(&mut self.chunk_counts)));
        self.chunk.clear();
        self.in_chunk.iter_mut().for_each(|b| *b = false);
        Ok(())
    }

    /// Writes the last chunk and the index, and rewrites the bag header; returns the output.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.flush_chunk()?;
        let index_pos = self.out.stream_position()?;
        let mut rec = Vec::new();
        for conn in 0..self.connections.len() as u32 {
            self.connection_record(&mut rec, conn);
        }
        for (pos, s, e, counts) in &self.chunk_infos {
            let data: Vec<u8> = counts
                .iter()
                .flat_map(|(c, n)| [c.to_le_bytes(), n.to_le_bytes()].concat())
                .collect();
            record(
                &mut rec,
                &[
                    field("op", &[op::CHUNK_INFO]),
                    field("ver", &1u32.to_le_bytes()),
                    field("chunk_pos", &pos.to_le_bytes()),
                    field("start_time", &time(*s)),
                    field("end_time", &time(*e)),
                    field("count", &(counts.len() as u32).to_le_bytes()),
                ],
                &data,
            );
        }
        self.out.write_all(&rec)?;
        self.out.seek(SeekFrom::Start(MAGIC.len() as u64))?;
        self.write_bag_header(index_pos)?;
        self.out.seek(SeekFrom::End(0))?;
        self.out.flush()?;
        Ok(self.out)
    }
}

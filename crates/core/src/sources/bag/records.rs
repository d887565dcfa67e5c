//! The ROS 1 bag v2.0 record layer, read as a stream.
//!
//! A bag is `#ROSBAG V2.0\n` then records: `u32` header length, header fields (`u32` length,
//! `name=value`), `u32` data length, data. Messages and their connections live in chunks
//! (compression `none`, `bz2` or `lz4`); the index (connections and chunk infos with per-connection
//! counts) follows the last chunk at `index_pos`.
//!
//! Our own reader rather than the `rosbag` crate (0.6.3): that crate memory-maps the whole file
//! (resident memory then grows with the pages touched, i.e. with the bag, and a file changed while
//! mapped is undefined behaviour) and links the C `lz4` library. Here one chunk at a time is read
//! through a `BufReader` and decompressed with `bzip2` and `lz4_flex` (pure Rust), so memory
//! follows the largest chunk (rosbag's default is 768 KiB), never the bag.

use std::io::Read;

use crate::error::{Error, Result};

/// The first bytes of every version 2.0 bag.
pub const MAGIC: &[u8; 13] = b"#ROSBAG V2.0\n";

/// Record op codes.
pub(crate) mod op {
    pub const MESSAGE_DATA: u8 = 0x02;
    pub const BAG_HEADER: u8 = 0x03;
    pub const INDEX_DATA: u8 = 0x04;
    pub const CHUNK: u8 = 0x05;
    pub const CHUNK_INFO: u8 = 0x06;
    pub const CONNECTION: u8 = 0x07;
}

/// A record header larger than this is damage, not data.
const MAX_HEADER: u32 = 16 << 20;

/// The fields of a record header (or of a connection record's data).
#[derive(Debug, Default)]
pub struct Fields<'a>(Vec<(&'a [u8], &'a [u8])>);

impl<'a> Fields<'a> {
    /// Parses `name=value` fields.
    pub fn parse(mut bytes: &'a [u8]) -> std::result::Result<Self, String> {
        let mut fields = Vec::new();
        while !bytes.is_empty() {
            let len = read_u32_slice(&mut bytes)? as usize;
            if len > bytes.len() {
                return Err(format!(
                    "header field of {len} bytes with {} left",
                    bytes.len()
                ));
            }
            let (field, rest) = bytes.split_at(len);
            bytes = rest;
            let eq = field
                .iter()
                .position(|&b| b == b'=')
                .ok_or("header field without `=`")?;
            fields.push((&field[..eq], &field[eq + 1..]));
        }
        Ok(Fields(fields))
    }

    /// The value of `name`.
    pub fn get(&self, name: &str) -> Option<&'a [u8]> {
        self.0
            .iter()
            .find(|(n, _)| *n == name.as_bytes())
            .map(|(_, v)| *v)
    }

    /// The value of `name` as text.
    pub fn text(&self, name: &str) -> Option<String> {
        self.get(name)
            .map(|v| String::from_utf8_lossy(v).into_owned())
    }

    /// The op code.
    pub fn op(&self) -> Option<u8> {
        self.get("op").and_then(|v| v.first().copied())
    }

    /// A little-endian `u32` field.
    pub fn u32(&self, name: &str) -> Option<u32> {
        let v = self.get(name)?;
        Some(u32::from_le_bytes(v.get(..4)?.try_into().ok()?))
    }

    /// A little-endian `u64` field.
    pub fn u64(&self, name: &str) -> Option<u64> {
        let v = self.get(name)?;
        Some(u64::from_le_bytes(v.get(..8)?.try_into().ok()?))
    }

    /// A ROS `time` field (`u32` secs, `u32` nsecs) in nanoseconds.
    pub fn time_ns(&self, name: &str) -> Option<u64> {
        let v = self.get(name)?;
        let secs = u32::from_le_bytes(v.get(..4)?.try_into().ok()?);
        let nsecs = u32::from_le_bytes(v.get(4..8)?.try_into().ok()?);
        Some(secs as u64 * 1_000_000_000 + nsecs as u64)
    }
}

/// Reads a `u32` off the front of a slice.
pub fn read_u32_slice(bytes: &mut &[u8]) -> std::result::Result<u32, String> {
    if bytes.len() < 4 {
        return Err(format!("{} bytes where a length was expected", bytes.len()));
    }
    let (n, rest) = bytes.split_at(4);
    *bytes = rest;
    Ok(u32::from_le_bytes([n[0], n[1], n[2], n[3]]))
}

/// Splits the records of an in-memory buffer (a decompressed chunk): `(header, data)` pairs.
pub fn split_records(mut bytes: &[u8]) -> std::result::Result<Vec<(Fields<'_>, &[u8])>, String> {
    let mut out = Vec::new();
    while !bytes.is_empty() {
        let hlen = read_u32_slice(&mut bytes)? as usize;
        if hlen > bytes.len() {
            return Err(format!(
                "record header of {hlen} bytes past the chunk's end"
            ));
        }
        let (h, rest) = bytes.split_at(hlen);
        bytes = rest;
        let dlen = read_u32_slice(&mut bytes)? as usize;
        if dlen > bytes.len() {
            return Err(format!("record data of {dlen} bytes past the chunk's end"));
        }
        let (d, rest) = bytes.split_at(dlen);
        bytes = rest;
        out.push((Fields::parse(h)?, d));
    }
    Ok(out)
}

/// What [`read_record`] found.
pub enum Next {
    /// A record: its header bytes are in `header`, its data length is returned (the data is not read).
    Record { data_len: u32 },
    /// The file ended cleanly between records.
    End,
    /// The file ended inside a record.
    Truncated,
}

/// Reads the next top-level record's header into `header` (the caller then reads or skips
/// `data_len` bytes). `remaining` is how many bytes the file holds from the record's start: a header
/// or data length past it is a file cut short ([`Next::Truncated`]), found before anything is
/// allocated, so a length field of 0xFFFFFFFF never costs 4 GB.
pub fn read_record<R: Read>(
    r: &mut R,
    header: &mut Vec<u8>,
    path: &std::path::Path,
    remaining: u64,
) -> Result<Next> {
    let mut len = [0u8; 4];
    match read_full(r, &mut len).map_err(|e| Error::io(path, e))? {
        0 => return Ok(Next::End),
        4 => {}
        _ => return Ok(Next::Truncated),
    }
    let hlen = u32::from_le_bytes(len);
    if hlen > MAX_HEADER {
        return Err(Error::CorruptBag {
            path: path.to_path_buf(),
            detail: format!("record header of {hlen} bytes"),
        });
    }
    if 8 + hlen as u64 > remaining {
        return Ok(Next::Truncated);
    }
    header.resize(hlen as usize, 0);
    if read_full(r, header).map_err(|e| Error::io(path, e))? < header.len() {
        return Ok(Next::Truncated);
    }
    if read_full(r, &mut len).map_err(|e| Error::io(path, e))? < 4 {
        return Ok(Next::Truncated);
    }
    let data_len = u32::from_le_bytes(len);
    if 8 + hlen as u64 + data_len as u64 > remaining {
        return Ok(Next::Truncated);
    }
    Ok(Next::Record { data_len })
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
pub fn read_full<R: Read>(r: &mut R, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

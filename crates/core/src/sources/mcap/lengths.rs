//! Checks every length prefix inside an MCAP record against the record's own bytes before the `mcap`
//! crate parses it.
//!
//! Why hand-written: `mcap` 0.26 reads a string field by allocating its declared `u32` length before
//! reading (binrw `count`), so one damaged length in a 5 KB file asks for up to 4 GB — in
//! `parse_record` and inside its `SummaryReader` (foxglove/mcap#1813 is the same family). The record
//! length limit does not help: the string length is inside a record of legal size. This walks each
//! record's layout (MCAP spec, "Records") and refuses any string, byte array or map that runs past
//! the record's end, so the crate is only handed records whose lengths are honest.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use mcap::records::op;

/// A cursor over one record's bytes that refuses any length past the end.
struct Walk<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Walk<'_> {
    fn skip(&mut self, n: u64, what: &str) -> Result<(), String> {
        let left = (self.data.len() - self.pos) as u64;
        if n > left {
            return Err(format!(
                "{what} of {n} bytes at record byte {}, with {left} left in the record",
                self.pos
            ));
        }
        self.pos += n as usize;
        Ok(())
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let at = self.pos;
        self.skip(4, what)?;
        Ok(u32::from_le_bytes(
            self.data[at..at + 4].try_into().unwrap_or([0; 4]),
        ))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let at = self.pos;
        self.skip(8, what)?;
        Ok(u64::from_le_bytes(
            self.data[at..at + 8].try_into().unwrap_or([0; 8]),
        ))
    }

    /// A `u32`-prefixed string or byte array.
    fn string(&mut self, what: &str) -> Result<(), String> {
        let n = self.u32(what)?;
        self.skip(n as u64, what)
    }

    /// A `u32` byte length, then `name=value` string pairs filling it exactly.
    fn string_map(&mut self, what: &str) -> Result<(), String> {
        let n = self.u32(what)? as u64;
        let left = (self.data.len() - self.pos) as u64;
        if n > left {
            return Err(format!(
                "{what} of {n} bytes, with {left} left in the record"
            ));
        }
        let end = self.pos as u64 + n;
        while (self.pos as u64) < end {
            self.string(what)?;
            self.string(what)?;
        }
        if self.pos as u64 != end {
            return Err(format!("{what} overruns its declared {n} bytes"));
        }
        Ok(())
    }

    /// A `u32` byte length, then fixed-size entries.
    fn fixed_map(&mut self, what: &str) -> Result<(), String> {
        let n = self.u32(what)?;
        self.skip(n as u64, what)
    }
}

/// `Ok` when every length inside the record of `opcode` fits in `data`; else what does not.
pub fn check_record(opcode: u8, data: &[u8]) -> Result<(), String> {
    let mut w = Walk { data, pos: 0 };
    match opcode {
        op::HEADER => {
            w.string("profile")?;
            w.string("library")
        }
        op::SCHEMA => {
            w.skip(2, "schema id")?;
            w.string("schema name")?;
            w.string("schema encoding")?;
            w.string("schema data")
        }
        op::CHANNEL => {
            w.skip(4, "channel ids")?;
            w.string("topic")?;
            w.string("message encoding")?;
            w.string_map("channel metadata")
        }
        op::MESSAGE => w.skip(22, "message header"),
        op::CHUNK => {
            w.skip(28, "chunk header")?;
            w.string("chunk compression")?;
            let n = w.u64("chunk records length")?;
            w.skip(n, "chunk records")
        }
        op::CHUNK_INDEX => {
            w.skip(32, "chunk index")?;
            w.fixed_map("message index offsets")?;
            w.skip(8, "message index length")?;
            w.string("chunk index compression")
        }
        op::ATTACHMENT => {
            w.skip(16, "attachment times")?;
            w.string("attachment name")?;
            w.string("attachment media type")?;
            let n = w.u64("attachment data length")?;
            w.skip(n, "attachment data")
        }
        op::ATTACHMENT_INDEX => {
            w.skip(40, "attachment index")?;
            w.string("attachment name")?;
            w.string("attachment media type")
        }
        op::STATISTICS => {
            w.skip(42, "statistics")?;
            w.fixed_map("channel message counts")
        }
        op::METADATA => {
            w.string("metadata name")?;
            w.string_map("metadata")
        }
        op::METADATA_INDEX => {
            w.skip(16, "metadata index")?;
            w.string("metadata name")
        }
        _ => Ok(()),
    }
}

/// The footer record (opcode, u64 length 20, summary_start, summary_offset_start, crc) and the end
/// magic after it.
const FOOTER: u64 = 1 + 8 + 20 + 8;

/// The footer and end magic of an MCAP `file` of `size` bytes; `None` when the file does not end with
/// them (a file cut short, even after its Data End record).
pub fn read_footer(
    file: &mut std::fs::File,
    size: u64,
) -> std::io::Result<Option<[u8; FOOTER as usize]>> {
    if size < 8 + FOOTER {
        return Ok(None);
    }
    let mut footer = [0u8; FOOTER as usize];
    file.seek(SeekFrom::Start(size - FOOTER))?;
    file.read_exact(&mut footer)?;
    Ok((footer[0] == op::FOOTER && footer[29..] == *mcap::MAGIC).then_some(footer))
}

/// Checks every record of the summary section of `path` (found through the footer) with
/// [`check_record`]; `Err` says what is damaged. A file without a footer or summary passes (there is
/// nothing the summary reader would parse). `limit` bounds the section read into memory.
pub fn check_summary(path: &Path, limit: u64) -> Result<(), String> {
    let mut file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let size = file.metadata().map_err(|e| e.to_string())?.len();
    let Some(footer) = read_footer(&mut file, size).map_err(|e| e.to_string())? else {
        return Ok(());
    };
    let summary_start = u64::from_le_bytes(footer[9..17].try_into().unwrap_or([0; 8]));
    let footer_start = size - FOOTER;
    if summary_start == 0 {
        return Ok(());
    }
    if summary_start > footer_start || footer_start - summary_start > limit {
        return Err(format!(
            "summary start {summary_start} outside the file or larger than {limit} bytes"
        ));
    }
    let mut section = vec![0u8; (footer_start - summary_start) as usize];
    file.seek(SeekFrom::Start(summary_start))
        .and_then(|_| file.read_exact(&mut section))
        .map_err(|e| e.to_string())?;
    let mut rest = section.as_slice();
    while !rest.is_empty() {
        if rest.len() < 9 {
            return Err("a summary record cut short".into());
        }
        let opcode = rest[0];
        let len = u64::from_le_bytes(rest[1..9].try_into().unwrap_or([0; 8]));
        if len > (rest.len() - 9) as u64 {
            return Err(format!("summary record of {len} bytes past the footer"));
        }
        let (data, next) = rest[9..].split_at(len as usize);
        check_record(opcode, data)?;
        rest = next;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_string_longer_than_its_record_is_refused() {
        let mut schema = vec![1, 0];
        schema.extend_from_slice(&u32::MAX.to_le_bytes());
        schema.extend_from_slice(b"name");
        assert!(check_record(op::SCHEMA, &schema).is_err());
        let mut ok = vec![1, 0];
        for s in ["pkg/msg/T", "ros2msg", "float64 x"] {
            ok.extend_from_slice(&(s.len() as u32).to_le_bytes());
            ok.extend_from_slice(s.as_bytes());
        }
        assert!(check_record(op::SCHEMA, &ok).is_ok());
        assert!(check_record(op::SCHEMA, &ok[..ok.len() - 1]).is_err());
    }
}

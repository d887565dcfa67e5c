//! What the annotated copy must know about the input before the copy pass starts: the schema and
//! channel ids it already uses (so the new channels never clash) and its chunk compression (kept in
//! the output). Read from the summary section; a file without one (a recorder that crashed) gets the
//! defaults, and the copy pass still detects a clash when it meets one.

use std::collections::BTreeSet;
use std::io::{Read, Seek};
use std::path::Path;

use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};

/// Ids and compression of an input recording.
#[derive(Debug, Clone, Default)]
pub struct InputInfo {
    pub schema_ids: BTreeSet<u16>,
    pub channel_ids: BTreeSet<u16>,
    /// The first chunk's compression (`zstd`, `lz4`, or empty for none); `None` when unknown.
    pub compression: Option<String>,
}

impl InputInfo {
    /// The output's compression: the input's, zstd when unknown or not supported.
    pub fn output_compression(&self) -> Option<mcap::Compression> {
        match self.compression.as_deref() {
            Some("") => None,
            Some("lz4") => Some(mcap::Compression::Lz4),
            _ => Some(mcap::Compression::Zstd),
        }
    }

    /// `n` ids, counting down from the top of the id space, none among `used` (ids 0 excluded).
    pub fn free_ids(used: &BTreeSet<u16>, n: usize) -> Vec<u16> {
        (1..=u16::MAX)
            .rev()
            .filter(|id| !used.contains(id))
            .take(n)
            .collect()
    }
}

/// Reads the ids and compression of `path` from its summary; defaults when there is none.
pub fn read_input_info(path: &Path) -> InputInfo {
    read(path).unwrap_or_default()
}

fn read(path: &Path) -> Option<InputInfo> {
    let mut file = std::fs::File::open(path).ok()?;
    let size = file.metadata().ok()?.len();
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(size)
            .with_record_length_limit(64 << 20),
    );
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(n) => {
                let read = file.read(reader.insert(n)).ok()?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = file.seek(to).ok()?;
                reader.notify_seeked(pos);
            }
        }
    }
    let summary = reader.finish()?;
    Some(InputInfo {
        schema_ids: summary.schemas.keys().copied().collect(),
        channel_ids: summary.channels.keys().copied().collect(),
        compression: summary.chunk_indexes.first().map(|c| c.compression.clone()),
    })
}

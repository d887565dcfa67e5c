//! What the annotated copy must know about the input before the copy pass starts: the schema and
//! channel ids it already uses (so the new channels never clash) and its chunk compression (kept in
//! the output). Read from the summary section; a file without one (a recorder that crashed) gets the
//! defaults, and the copy pass still detects a clash when it meets one.

use std::collections::BTreeSet;
use std::path::Path;

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
    let summary = crate::sources::mcap::summary::read_mcap_summary(path)?;
    Some(InputInfo {
        schema_ids: summary.schemas.keys().copied().collect(),
        channel_ids: summary.channels.keys().copied().collect(),
        compression: summary.chunk_indexes.first().map(|c| c.compression.clone()),
    })
}

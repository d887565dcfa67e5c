//! The summary section at the end of an MCAP file: channels and message counts without reading the
//! data, so that `topics` is instant and `extract` can reject a wrong topic before the pass.
//!
//! Optional by the format: a file without summary (or one cut short, which has no footer) reads as
//! `None` and the callers fall back to the streaming pass.

use std::collections::HashMap;
use std::io::{Read, Seek};
use std::path::Path;

use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};

use crate::sources::recording::ChannelInfo;

/// What the summary says.
#[derive(Debug, Clone, Default)]
pub struct SummaryInfo {
    /// Channels listed in the summary, by id.
    pub channels: Vec<ChannelInfo>,
    /// Messages per channel id, when the summary holds a Statistics record.
    pub message_counts: Option<HashMap<u16, u64>>,
}

/// The raw summary section of `path` (schemas, channels, statistics, chunk indexes), read with the
/// sans-io summary reader: `None` when there is none or it cannot be read. Shared by the source and the
/// annotated-copy writer.
pub fn read_mcap_summary(path: &Path) -> Option<mcap::Summary> {
    // Every length inside the summary's records checked first (the crate trusts them): a damaged
    // summary reads as none, and the streaming pass (which checks each record too) names the damage.
    super::lengths::check_summary(path, 64 << 20).ok()?;
    let mut file = std::fs::File::open(path).ok()?;
    let size = file.metadata().ok()?.len();
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(size)
            // The summary of a file of gigabytes is kilobytes; a longer record is damage.
            .with_record_length_limit(64 << 20),
    );
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(n) => {
                // The reader zero-fills what it asks for: never more than the file holds.
                let n = n.min(
                    usize::try_from(size)
                        .unwrap_or(usize::MAX)
                        .saturating_add(1),
                );
                let read = file.read(reader.insert(n)).ok()?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = file.seek(to).ok()?;
                reader.notify_seeked(pos);
            }
        }
    }
    reader.finish()
}

/// Reads the summary of `path`. `None` when the file has no summary, no channel in it, or no valid
/// footer (a truncated file): the caller reads the data section instead.
pub fn read_summary(path: &Path) -> Option<SummaryInfo> {
    let summary = read_mcap_summary(path)?;
    if summary.channels.is_empty() {
        return None;
    }
    let mut channels: Vec<ChannelInfo> = summary
        .channels
        .values()
        .map(|c| {
            let (schema_name, schema_encoding, schema_data) = c
                .schema
                .as_ref()
                .map(|s| (s.name.clone(), s.encoding.clone(), s.data.as_ref().into()))
                .unwrap_or_default();
            ChannelInfo {
                id: c.id,
                topic: c.topic.clone(),
                schema_name,
                schema_encoding,
                message_encoding: c.message_encoding.clone(),
                schema_data,
            }
        })
        .collect();
    channels.sort_by_key(|c| c.id);
    // Per-channel counts are optional within Statistics: an empty map with messages means "not counted".
    let message_counts = summary
        .stats
        .filter(|s| s.message_count == 0 || !s.channel_message_counts.is_empty())
        .map(|s| {
            s.channel_message_counts
                .into_iter()
                .collect::<HashMap<u16, u64>>()
        });
    Some(SummaryInfo {
        channels,
        message_counts,
    })
}

//! `metadata.yaml` of a rosbag2 folder: storage plugin, split files and topics with their counts.

use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};

/// The top level of `metadata.yaml`.
#[derive(Debug, Deserialize)]
struct File {
    rosbag2_bagfile_information: Metadata,
}

/// What trajdrift uses of `rosbag2_bagfile_information`.
#[derive(Debug, Clone, Deserialize)]
pub struct Metadata {
    /// `mcap` or `sqlite3`.
    pub storage_identifier: String,
    /// The split files, relative to the folder, in recording order.
    pub relative_file_paths: Vec<String>,
    #[serde(default)]
    pub topics_with_message_count: Vec<TopicWithCount>,
    /// `zstd` when files or messages are compressed; empty otherwise.
    #[serde(default)]
    pub compression_format: Option<String>,
}

/// One topic and how many messages it has.
#[derive(Debug, Clone, Deserialize)]
pub struct TopicWithCount {
    #[serde(default)]
    pub message_count: u64,
    pub topic_metadata: TopicMetadata,
}

/// A topic's name, type and serialization.
#[derive(Debug, Clone, Deserialize)]
pub struct TopicMetadata {
    pub name: String,
    #[serde(rename = "type")]
    pub type_name: String,
    #[serde(default = "cdr")]
    pub serialization_format: String,
}

fn cdr() -> String {
    "cdr".into()
}

/// Reads `<dir>/metadata.yaml`.
pub fn read(dir: &Path) -> Result<Metadata> {
    let path = dir.join("metadata.yaml");
    let bad = |detail: String| Error::Rosbag2 {
        path: dir.to_path_buf(),
        detail,
    };
    // metadata.yaml lists the files and topics: a few kilobytes, 16 MiB for the largest recordings.
    let text = crate::sources::input::read_text_bounded(&path, 16 << 20, "rosbag2 metadata.yaml")
        .map_err(|e| {
        bad(format!(
            "cannot read metadata.yaml ({e}); pass a rosbag2 folder, a .bag or a .mcap file"
        ))
    })?;
    let file: File = serde_yaml_ng::from_str(&text).map_err(|e| {
        bad(format!(
            "metadata.yaml: {e}; re-create it with `ros2 bag reindex`"
        ))
    })?;
    Ok(file.rosbag2_bagfile_information)
}

//! Picks the reader for a RECORDING argument: a rosbag2 folder, a ROS 1 bag or an MCAP file.
use std::path::Path;

use crate::error::{Error, Result};
use crate::sources::bag::BagSource;
use crate::sources::mcap::McapSource;
use crate::sources::rosbag2::Rosbag2Source;
use crate::sources::Source;

/// Opens a recording by its content: a folder with `metadata.yaml` is a rosbag2 recording, a file
/// starting with `#ROSBAG` a ROS 1 bag, anything else is read as MCAP (which names the problem
/// when it is not one).
pub fn open(path: &Path) -> Result<Box<dyn Source + Send + Sync>> {
    if path.is_dir() {
        return Ok(Box::new(Rosbag2Source::open(path)?));
    }
    if path.file_name().is_some_and(|n| n == "metadata.yaml") {
        if let Some(dir) = path.parent() {
            return Ok(Box::new(Rosbag2Source::open(dir)?));
        }
    }
    let mut head = [0u8; 8];
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let n = super::bag::records::read_full(&mut file, &mut head).map_err(|e| Error::io(path, e))?;
    if head[..n].starts_with(b"#ROSBAG") {
        return Ok(Box::new(BagSource::open(path)?));
    }
    Ok(Box::new(McapSource::open(path)?))
}

/// True when `path` is a recording [`open`] reads (a rosbag2 folder or its metadata.yaml, a file
/// starting with the ROS 1 bag or MCAP magic, or named `.mcap`/`.bag`), false for anything else
/// (a text trajectory), so commands that take both can tell them apart.
pub fn is_recording(path: &Path) -> bool {
    if path.is_dir() || path.file_name().is_some_and(|n| n == "metadata.yaml") {
        return true;
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap") || e.eq_ignore_ascii_case("bag"))
    {
        return true;
    }
    let mut head = [0u8; 8];
    let n = std::fs::File::open(path)
        .and_then(|mut f| super::bag::records::read_full(&mut f, &mut head))
        .unwrap_or(0);
    head[..n].starts_with(b"#ROSBAG") || head[..n] == *mcap::MAGIC
}

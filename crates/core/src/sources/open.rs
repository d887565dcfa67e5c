//! Picks the reader for a RECORDING argument: a rosbag2 folder, a ROS 1 bag, an MCAP file, or a
//! mission of several of them (files given together, or a folder of them).
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::sources::bag::BagSource;
use crate::sources::mcap::McapSource;
use crate::sources::mission::{Mission, Part};
use crate::sources::rosbag2::Rosbag2Source;
use crate::sources::Source;

/// Opens a recording by its content: a folder with `metadata.yaml` is a rosbag2 recording, any other
/// folder a mission folder ([`recordings_in`]), a file starting with `#ROSBAG` a ROS 1 bag, anything
/// else is read as MCAP (which names the problem when it is not one).
pub fn open(path: &Path) -> Result<Box<dyn Source + Send + Sync>> {
    Ok(Box::new(open_recording(path)?))
}

/// [`open`] of one or more paths: several are one [`Mission`], named after the first.
pub fn open_all(paths: &[PathBuf]) -> Result<Box<dyn Source + Send + Sync>> {
    match paths {
        [] => Err(Error::InvalidArgument("no RECORDING given".into())),
        [one] => open(one),
        [first, ..] => {
            let parts = paths
                .iter()
                .map(|p| open_recording(p))
                .collect::<Result<Vec<Part>>>()?;
            Ok(Box::new(Mission::new(first, parts)?))
        }
    }
}

/// [`open`] as a [`crate::sources::recording::Recording`].
pub fn open_recording(path: &Path) -> Result<Part> {
    if path.is_dir() {
        if !path.join("metadata.yaml").is_file() {
            let parts = recordings_in(path)?
                .iter()
                .map(|p| open_recording(p))
                .collect::<Result<Vec<Part>>>()?;
            return Ok(Box::new(Mission::new(path, parts)?));
        }
        return Ok(Box::new(Rosbag2Source::open(path)?));
    }
    if path.file_name().is_some_and(|n| n == "metadata.yaml") {
        if let Some(dir) = path.parent() {
            return Ok(Box::new(Rosbag2Source::open(dir)?));
        }
    }
    super::input::require_seekable(path, "a recording")?;
    let mut head = [0u8; 8];
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let n = super::bag::records::read_full(&mut file, &mut head).map_err(|e| Error::io(path, e))?;
    if head[..n].starts_with(b"#ROSBAG") {
        return Ok(Box::new(BagSource::open(path)?));
    }
    Ok(Box::new(McapSource::open(path)?))
}

/// The recordings directly inside a mission folder, sorted by name: `*.mcap` and `*.bag` files and
/// rosbag2 folders (a folder holding `metadata.yaml`). Hidden files (a `.name.tmp` being written) are
/// skipped. An error when there is none.
pub fn recordings_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut out: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            !p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .filter(|p| is_recording_entry(p))
        .collect();
    out.sort();
    if out.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "{}: a folder without metadata.yaml is read as a mission folder, and it holds no recording (.mcap, .bag or rosbag2 folder)",
            dir.display()
        )));
    }
    Ok(out)
}

/// A `*.mcap` or `*.bag` file, or a rosbag2 folder.
pub fn is_recording_entry(p: &Path) -> bool {
    if p.is_dir() {
        return p.join("metadata.yaml").is_file();
    }
    p.is_file()
        && p.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mcap") || e.eq_ignore_ascii_case("bag"))
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
    // A stream (a pipe, a FIFO) is read once and kept, so looking at its first bytes loses nothing.
    let n = if super::input::is_stream(path) {
        super::input::open_text(path)
            .ok()
            .and_then(|mut f| super::bag::records::read_full(&mut f, &mut head).ok())
            .unwrap_or(0)
    } else {
        std::fs::File::open(path)
            .and_then(|mut f| super::bag::records::read_full(&mut f, &mut head))
            .unwrap_or(0)
    };
    head[..n].starts_with(b"#ROSBAG") || head[..n] == *mcap::MAGIC
}

/// Bytes of an input for a progress bar: a file's size, or the sum over a folder's files (two levels
/// down at most, each folder counted once: a symlink loop ends).
pub fn input_size(path: &Path) -> u64 {
    fn walk(path: &Path, depth: usize, seen: &mut Vec<PathBuf>) -> u64 {
        if !path.is_dir() {
            return std::fs::metadata(path).map_or(0, |m| m.len());
        }
        let Ok(real) = path.canonicalize() else {
            return 0;
        };
        if depth > 2 || seen.contains(&real) {
            return 0;
        }
        seen.push(real);
        std::fs::read_dir(path)
            .map(|entries| {
                entries
                    .filter_map(|e| e.ok())
                    .map(|e| walk(&e.path(), depth + 1, seen))
                    .sum()
            })
            .unwrap_or(0)
    }
    walk(path, 0, &mut Vec::new())
}

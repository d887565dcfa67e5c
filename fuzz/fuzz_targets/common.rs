#![allow(dead_code)]
//! Shared by the file-based targets: the readers take paths, so each input is written to a file on
//! tmpfs (one per process) and read through the same public API the CLI uses.

use std::path::PathBuf;

use trajdrift_core::sources::{ExtractOptions, Source};

/// Writes `data` to this process's scratch file with extension `ext`.
pub fn scratch(data: &[u8], ext: &str) -> PathBuf {
    let dir = if std::path::Path::new("/dev/shm").is_dir() {
        PathBuf::from("/dev/shm")
    } else {
        std::env::temp_dir()
    };
    let path = dir.join(format!("trajdrift-fuzz-{}.{ext}", std::process::id()));
    std::fs::write(&path, data).expect("scratch file");
    path
}

/// Everything a user can ask of a recording: its topics, its TF frames, every readable topic's
/// trajectory, with log and header stamps. Errors are fine; panics, hangs and OOMs are not.
pub fn exercise(source: &dyn Source) {
    let Ok(topics) = source.topics() else {
        return;
    };
    let _ = source.frame_pairs_checked(&|_| {});
    let readable: Vec<String> = topics
        .iter()
        .filter(|t| t.readable)
        .map(|t| t.topic.clone())
        .collect();
    let _ = source.extract(&readable, &ExtractOptions::default(), &|_| {});
    if let Some(first) = readable.first() {
        let options = ExtractOptions {
            stamp: trajdrift_core::sources::StampSource::Log,
            ..ExtractOptions::default()
        };
        let _ = source.extract(std::slice::from_ref(first), &options, &|_| {});
    }
}

//! What makes a batch result trustworthy later: each per-mission result carries a [`Fingerprint`] of
//! the parameters and of the inputs it was computed from, each run writes a [`RunRecord`] (which
//! missions it was asked for, with which parameters, as which shard), and a [`BatchLock`] on the output
//! folder keeps two runs from writing the same results at once.
//!
//! - **Parameters**: a 128-bit hash (XXH3) of the trajdrift version and the mission's whole evaluation
//!   request — topics, names, every parameter, input paths made absolute — so any change that can
//!   change a number changes it.
//! - **Inputs**: a hash over every input file's size, modification time and last 64 KiB (where an MCAP
//!   keeps its summary and a ROS 1 bag its index), folders walked in name order (three levels at most,
//!   each folder once). Reading the tail catches a recording replaced by another of the same size and
//!   time (`cp -p`) without reading the recording. An input that is a stream cannot be fingerprinted:
//!   its result is never reused.
//!
//! `batch --skip-existing` reuses a result only when both match the mission as it is now; `merge`
//! compares the results with the run records (see [`super::merge`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::shard::Shard;
use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, TrajectoryInput};
use crate::output::{lock, resolve};

/// Marks a run record file.
pub const RUN_KIND: &str = "trajdrift.run";

/// Bytes hashed at the end of each input file.
const TAIL_BYTES: u64 = 64 * 1024;

/// What a per-mission result was computed from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// Hash of the trajdrift version and the mission's evaluation request (32 hex digits).
    pub parameters: String,
    /// Hash of the inputs' sizes, times and tails; `None` when an input is missing or a stream.
    pub inputs: Option<String>,
}

impl Fingerprint {
    /// The fingerprint of `config` as it is now.
    pub fn of(config: &EvalConfig) -> Fingerprint {
        Fingerprint {
            parameters: parameters_fingerprint(config),
            inputs: inputs_fingerprint(config),
        }
    }
}

fn hex(v: u128) -> String {
    format!("{v:032x}")
}

/// The parameters' hash of `config`: the version and the whole request, input paths absolute (the same
/// manifest run from another folder names the same files).
pub fn parameters_fingerprint(config: &EvalConfig) -> String {
    let mut c = config.clone();
    c.recording = c.recording.as_deref().map(resolve);
    c.more_recordings = c.more_recordings.iter().map(|p| resolve(p)).collect();
    for input in std::iter::once(&mut c.reference).chain(c.estimates.iter_mut()) {
        if let TrajectoryInput::TumFile(p) = &mut input.input {
            *p = resolve(p);
        }
    }
    c.text.kitti_times = c.text.kitti_times.as_deref().map(resolve);
    c.keep_orientations = false;
    let text = format!("trajdrift {}\n{c:?}", env!("CARGO_PKG_VERSION"));
    hex(twox_hash::XxHash3_128::oneshot(text.as_bytes()))
}

/// The inputs' hash of `config`, `None` when one is missing or not a regular file or folder.
pub fn inputs_fingerprint(config: &EvalConfig) -> Option<String> {
    let mut h = twox_hash::XxHash3_128::new();
    let mut seen = Vec::new();
    let mut paths = config.input_paths();
    paths.extend(config.more_recordings.iter().cloned());
    for p in paths {
        h.write(p.as_os_str().as_encoded_bytes());
        add_path(&mut h, &p, 0, &mut seen)?;
    }
    Some(hex(h.finish_128()))
}

fn add_path(
    h: &mut twox_hash::XxHash3_128,
    p: &Path,
    depth: usize,
    seen: &mut Vec<PathBuf>,
) -> Option<()> {
    let m = std::fs::metadata(p).ok()?;
    if m.is_file() {
        let mtime_ns = m
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos());
        h.write(&m.len().to_le_bytes());
        h.write(&mtime_ns.to_le_bytes());
        h.write(&tail(p, m.len())?);
        return Some(());
    }
    if !m.is_dir() {
        return None;
    }
    let real = p.canonicalize().ok()?;
    if depth >= 3 || seen.contains(&real) {
        return Some(());
    }
    seen.push(real);
    let mut entries: Vec<PathBuf> = std::fs::read_dir(p)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|q| {
            !q.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .collect();
    entries.sort();
    for q in entries {
        h.write(q.file_name()?.as_encoded_bytes());
        add_path(h, &q, depth + 1, seen)?;
    }
    Some(())
}

fn tail(p: &Path, len: u64) -> Option<Vec<u8>> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = std::fs::File::open(p).ok()?;
    let start = len.saturating_sub(TAIL_BYTES);
    f.seek(SeekFrom::Start(start)).ok()?;
    let mut v = Vec::new();
    f.take(TAIL_BYTES).read_to_end(&mut v).ok()?;
    Some(v)
}

/// Whether a run was still going when its record was last written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// Written when the run starts: a run killed before its end leaves it so.
    Running,
    /// Every mission of the run has its result and the summary is written.
    Complete,
}

/// Shard I of N, as recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardRecord {
    pub index: usize,
    pub count: usize,
}

/// `trajdrift-run.json` (or `trajdrift-run-shard-I-of-N.json`): what one batch run was asked to do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Always [`RUN_KIND`].
    pub kind: String,
    /// The same for every shard of one batch: a hash of the missions, their parameters and the shard
    /// count.
    pub run_id: String,
    /// Hash over every mission's parameters (the whole batch, not only this shard).
    pub parameters: String,
    /// Every mission of the batch (all shards) with its parameters' fingerprint, in name order.
    pub missions: std::collections::BTreeMap<String, String>,
    /// This run's shard, when sharded.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub shard: Option<ShardRecord>,
    /// The missions this run (shard) was asked for, in name order.
    pub selected: Vec<String>,
    pub status: RunStatus,
    pub trajdrift_version: String,
    /// Seconds since 1970 when the run started.
    pub started_unix_s: u64,
}

impl RunRecord {
    /// The record of a run of `all` (name, request) as `shard`, asked for `selected`.
    pub fn new(all: &[(&str, &EvalConfig)], shard: Option<Shard>, selected: &[&str]) -> RunRecord {
        let missions: std::collections::BTreeMap<String, String> = all
            .iter()
            .map(|(n, c)| (n.to_string(), parameters_fingerprint(c)))
            .collect();
        let mut h = twox_hash::XxHash3_128::new();
        for (n, f) in &missions {
            h.write(n.as_bytes());
            h.write(b"\0");
            h.write(f.as_bytes());
            h.write(b"\n");
        }
        let parameters = hex(h.finish_128());
        h.write(&shard.map_or(0, |s| s.count).to_le_bytes());
        let mut selected: Vec<String> = selected.iter().map(|s| s.to_string()).collect();
        selected.sort();
        RunRecord {
            kind: RUN_KIND.into(),
            run_id: hex(h.finish_128()),
            parameters,
            missions,
            shard: shard.map(|s| ShardRecord {
                index: s.index,
                count: s.count,
            }),
            selected,
            status: RunStatus::Running,
            trajdrift_version: env!("CARGO_PKG_VERSION").into(),
            started_unix_s: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        }
    }

    /// The record's file name in the output folder.
    pub fn file_name(shard: Option<Shard>) -> String {
        match shard {
            Some(s) => format!("trajdrift-run-shard-{}-of-{}.json", s.index, s.count),
            None => "trajdrift-run.json".into(),
        }
    }
}

/// The lock a batch holds on its output folder while it runs: an unsharded run holds the folder alone;
/// the shards of a run share it, each holding its own shard alone (the tasks of a job array write into
/// one folder at once). Released when dropped, or when the process ends however it ends.
#[derive(Debug)]
pub struct BatchLock {
    _folder: std::fs::File,
    _shard: Option<std::fs::File>,
}

impl BatchLock {
    /// Takes the lock of `dir` for a run as `shard`; refused at once ([`Error::OutputBusy`], exit 2)
    /// when another run holds what this one needs.
    pub fn acquire(dir: &Path, shard: Option<Shard>) -> Result<BatchLock> {
        let open = |name: &str| -> Result<(PathBuf, std::fs::File)> {
            let p = dir.join(name);
            let f = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&p)
                .map_err(|e| Error::output(&p, &e))?;
            Ok((p, f))
        };
        let busy = |p: &Path, what: &str| Error::OutputBusy {
            path: dir.to_path_buf(),
            what: what.into(),
            holder: format!(
                "it holds {}{}",
                p.display(),
                std::fs::read_to_string(p)
                    .ok()
                    .filter(|s| !s.trim().is_empty())
                    .map_or(String::new(), |s| format!(": {}", s.trim()))
            ),
        };
        let (folder_path, folder) = open(".trajdrift-batch.lock")?;
        let io = |p: &Path, e: std::io::Error| Error::output(p, &e);
        match shard {
            None => {
                if !lock::try_exclusive(&folder).map_err(|e| io(&folder_path, e))? {
                    return Err(busy(&folder_path, "batch"));
                }
                write_holder(&folder);
                Ok(BatchLock {
                    _folder: folder,
                    _shard: None,
                })
            }
            Some(s) => {
                if !lock::try_shared(&folder).map_err(|e| io(&folder_path, e))? {
                    return Err(busy(&folder_path, "batch (not sharded)"));
                }
                let (shard_path, own) = open(&format!(
                    ".trajdrift-batch-shard-{}-of-{}.lock",
                    s.index, s.count
                ))?;
                if !lock::try_exclusive(&own).map_err(|e| io(&shard_path, e))? {
                    return Err(busy(
                        &shard_path,
                        &format!("batch shard {}/{}", s.index, s.count),
                    ));
                }
                write_holder(&own);
                Ok(BatchLock {
                    _folder: folder,
                    _shard: Some(own),
                })
            }
        }
    }
}

/// Notes who holds a lock (for the refusal message of the next run); best effort.
fn write_holder(f: &std::fs::File) {
    use std::io::{Seek, Write};
    let mut f = f;
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_default();
    let _ = f.set_len(0);
    let _ = f.seek(std::io::SeekFrom::Start(0));
    let _ = write!(
        f,
        "process {}{} since {} s after 1970",
        std::process::id(),
        if host.is_empty() {
            String::new()
        } else {
            format!(" on {host}")
        },
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs())
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::config::NamedInput;

    fn config(dir: &Path) -> EvalConfig {
        EvalConfig::new(
            None,
            NamedInput::file(&dir.join("r.tum").to_string_lossy()),
            vec![NamedInput::file(&dir.join("e.tum").to_string_lossy())],
        )
    }

    #[test]
    fn fingerprints_follow_parameters_and_inputs() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("r.tum"), "1 0 0 0\n").unwrap();
        std::fs::write(dir.path().join("e.tum"), "1 0 0 0\n").unwrap();
        let c = config(dir.path());
        let a = Fingerprint::of(&c);
        assert_eq!(a, Fingerprint::of(&c));
        let mut w = c.clone();
        w.params.window = Some(vec![10.0]);
        assert_ne!(a.parameters, Fingerprint::of(&w).parameters);
        assert_eq!(a.inputs, Fingerprint::of(&w).inputs);
        // Same size, same time, other content.
        let e = dir.path().join("e.tum");
        let t = std::fs::metadata(&e).unwrap().modified().unwrap();
        std::fs::write(&e, "2 0 0 0\n").unwrap();
        std::fs::File::options()
            .write(true)
            .open(&e)
            .unwrap()
            .set_modified(t)
            .unwrap();
        assert_ne!(a.inputs, Fingerprint::of(&c).inputs);
        std::fs::remove_file(&e).unwrap();
        assert_eq!(Fingerprint::of(&c).inputs, None);
    }

    #[test]
    fn a_second_run_is_refused_while_shards_share_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let one = BatchLock::acquire(dir.path(), None).unwrap();
        let e = BatchLock::acquire(dir.path(), None).unwrap_err();
        assert!(matches!(e, Error::OutputBusy { .. }), "{e}");
        assert!(e.to_string().contains("process"), "{e}");
        assert!(BatchLock::acquire(dir.path(), Some(Shard { index: 1, count: 2 })).is_err());
        drop(one);
        let s1 = BatchLock::acquire(dir.path(), Some(Shard { index: 1, count: 2 })).unwrap();
        let _s2 = BatchLock::acquire(dir.path(), Some(Shard { index: 2, count: 2 })).unwrap();
        assert!(BatchLock::acquire(dir.path(), Some(Shard { index: 1, count: 2 })).is_err());
        assert!(BatchLock::acquire(dir.path(), None).is_err());
        drop(s1);
    }
}

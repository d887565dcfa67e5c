//! A regular file written whole or not at all: [`AtomicFile`] writes into a temporary file beside the
//! target (`.NAME.TOKEN.tmp`, hidden, in the same folder so that the rename stays on one file system)
//! and renames it onto the target when complete. The temporary file is removed on every failure: a
//! write, the sync or the rename failing, or the writer dropped without a commit.
//!
//! A run killed outright (SIGKILL, power loss) cannot remove its temporary file. The writer holds an
//! advisory lock ([`super::lock`]) on it from creation to rename, so the next writer of the same name
//! recognises a stale one by the lock nobody holds — not by a process id, which means nothing in
//! another PID namespace (a container, another host on a network file system) and may have been reused.
//! A sweeper takes the lock before it removes; a writer that took its lock checks afterwards that its
//! name still names its file, so a file created a moment before the sweep ran is never lost.

use std::fs::File;
use std::path::{Path, PathBuf};

use super::lock;
use crate::error::{Error, Result};

/// A file being written: a temporary file beside the target until [`AtomicFile::commit`] renames it;
/// dropped without a commit, the temporary file is removed.
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    file: Option<File>,
}

impl AtomicFile {
    /// Creates the locked temporary file for `path` (after removing stale ones of the same name).
    pub fn create(path: &Path) -> Result<AtomicFile> {
        let dir = folder_of(path);
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| Error::Output {
                path: path.to_path_buf(),
                detail: "not a file name; give a file, not a folder".into(),
            })?;
        remove_stale_temps(dir, &name);
        // A sweeper of another process may remove the file between its creation and our lock; then
        // the name no longer names our file and we start again (with a fresh token).
        for _ in 0..16 {
            let tmp = dir.join(temp_name(&name, &token()));
            let file = std::fs::OpenOptions::new()
                .write(true)
                .read(true)
                .create_new(true)
                .open(&tmp)
                .map_err(|e| Error::output(path, &e))?;
            lock::exclusive(&file).map_err(|e| Error::output(path, &e))?;
            if lock::names_file(&tmp, &file) {
                return Ok(AtomicFile {
                    path: path.to_path_buf(),
                    tmp,
                    file: Some(file),
                });
            }
        }
        Err(Error::Output {
            path: path.to_path_buf(),
            detail: "its temporary file kept disappearing (another process is sweeping this folder); try again".into(),
        })
    }

    /// The temporary file, to write into.
    pub fn file(&mut self) -> &mut File {
        self.file
            .as_mut()
            .expect("an AtomicFile is used until committed")
    }

    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The temporary file's path (for writers that must name a file, e.g. a PNG encoder).
    pub fn temp_path(&self) -> &Path {
        &self.tmp
    }

    /// Syncs the temporary file and renames it onto the target; on failure the temporary file is
    /// removed and the target left as it was.
    pub fn commit(mut self) -> Result<()> {
        let file = self.file.as_ref().expect("committed once");
        let done = file
            .sync_all()
            .and_then(|_| std::fs::rename(&self.tmp, &self.path));
        match done {
            Ok(()) => {
                // Renamed: nothing to remove any more; closing the file releases the lock.
                self.file = None;
                Ok(())
            }
            // Drop removes the temporary file (the lock still held, so no sweeper races us).
            Err(e) => Err(Error::output(&self.path, &e)),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.file.is_some() {
            let _ = std::fs::remove_file(&self.tmp);
            self.file = None;
        }
    }
}

/// The folder a file is written in (`.` for a bare name).
pub(crate) fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// `.NAME.TOKEN.tmp`: hidden (folder scans skip it) and ours.
fn temp_name(name: &str, token: &str) -> String {
    format!(".{name}.{token}.tmp")
}

/// 16 hex digits, different for every call (a randomly keyed hash of a counter, the process id and
/// the time), so that writers in different processes, PID namespaces or hosts never share a name.
fn token() -> String {
    use std::hash::{BuildHasher, Hasher};
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    h.write_u32(std::process::id());
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    format!("{:016x}", h.finish())
}

/// Removes this folder's temporary files of `name` (`.NAME.*.tmp`, also the `.NAME.*.tmp.png` of
/// earlier versions) that no writer holds: their writer was killed. A live writer's file is locked
/// and left alone, whichever process, container or host holds it.
pub fn remove_stale_temps(dir: &Path, name: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let prefix = format!(".{name}.");
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(n) = file_name.to_str() else {
            continue;
        };
        let ours = n
            .strip_prefix(&prefix)
            .is_some_and(|rest| rest.ends_with(".tmp") || rest.ends_with(".tmp.png"));
        if ours && entry.file_type().is_ok_and(|t| t.is_file()) {
            remove_if_unlocked(&entry.path());
        }
    }
}

/// Removes every stale temporary file of ours in `dir`, whatever its target's name (a batch's output
/// folder at the start of a run).
pub fn remove_all_stale_temps(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(n) = file_name.to_str() else {
            continue;
        };
        if n.starts_with('.')
            && (n.ends_with(".tmp") || n.ends_with(".tmp.png"))
            && entry.file_type().is_ok_and(|t| t.is_file())
        {
            remove_if_unlocked(&entry.path());
        }
    }
}

fn remove_if_unlocked(path: &Path) {
    let Ok(file) = File::open(path) else {
        return;
    };
    if lock::try_exclusive(&file).unwrap_or(false) && lock::names_file(path, &file) {
        let _ = std::fs::remove_file(path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn a_live_writers_temp_file_survives_a_sweep_and_a_dead_ones_does_not() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.json");
        let mut live = AtomicFile::create(&target).unwrap();
        live.file().write_all(b"{").unwrap();
        let live_tmp = live.temp_path().to_path_buf();
        // A killed writer's file: present, unlocked (old PID-named ones too).
        let dead = dir.path().join(".out.json.1.tmp");
        std::fs::write(&dead, "half").unwrap();
        let other = dir.path().join(".other.json.1.tmp");
        std::fs::write(&other, "not for this output").unwrap();
        remove_stale_temps(dir.path(), "out.json");
        assert!(live_tmp.exists(), "a live writer's file was removed");
        assert!(!dead.exists());
        assert!(other.exists());
        live.file().write_all(b"}").unwrap();
        live.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"{}");
        assert!(!live_tmp.exists());
        remove_all_stale_temps(dir.path());
        assert!(!other.exists());
    }

    #[test]
    fn a_failed_rename_or_a_drop_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        // The target is a non-empty folder: the rename fails.
        let target = dir.path().join("taken");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("x"), "x").unwrap();
        let mut f = AtomicFile::create(&target).unwrap();
        f.file().write_all(b"data").unwrap();
        assert!(f.commit().is_err());
        let dropped = AtomicFile::create(&dir.path().join("never.json")).unwrap();
        drop(dropped);
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, vec![std::ffi::OsString::from("taken")], "{left:?}");
    }
}

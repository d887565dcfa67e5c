//! The one way trajdrift writes a file: the [`OutputGuard`] refuses an output that resolves to an
//! input (the same path after canonicalisation, a symlink to it, a hard link with the same device and
//! inode, or a file inside an input folder), and the [`AtomicFile`] writes into a temporary file
//! beside the target and renames it when complete, so a crash never leaves a half-written file and
//! a reader never sees one. Temporary files of ours left by a killed run (`.NAME.PID.tmp` whose
//! process is gone) are removed when the same output is written again. `-` means standard output.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// One input as the guard compares it.
#[derive(Debug, Clone)]
struct InputId {
    given: PathBuf,
    canonical: Option<PathBuf>,
    /// (device, inode) on Unix.
    file_id: Option<(u64, u64)>,
    is_dir: bool,
}

/// The inputs of a command; [`OutputGuard::check`] refuses any output that would overwrite one.
#[derive(Debug, Clone, Default)]
pub struct OutputGuard {
    inputs: Vec<InputId>,
}

impl OutputGuard {
    /// A guard over `inputs` (paths that do not exist are kept by name).
    pub fn new<P: AsRef<Path>>(inputs: impl IntoIterator<Item = P>) -> Self {
        let mut g = OutputGuard::default();
        for p in inputs {
            g.add(p.as_ref());
        }
        g
    }

    /// Adds one input.
    pub fn add(&mut self, path: &Path) {
        if path.as_os_str() == "-" {
            return;
        }
        let meta = std::fs::metadata(path).ok();
        self.inputs.push(InputId {
            given: path.to_path_buf(),
            canonical: canonical(path),
            file_id: meta.as_ref().and_then(file_id),
            is_dir: meta.is_some_and(|m| m.is_dir()),
        });
    }

    /// Refuses `out` (given with `flag`) when it resolves to an input: [`Error::OutputIsInput`], which
    /// is a usage error (exit 2). `-` (standard output) is always allowed.
    pub fn check(&self, flag: &str, out: &Path) -> Result<()> {
        if out.as_os_str() == "-" {
            return Ok(());
        }
        let out_canon = canonical(out);
        let out_id = std::fs::metadata(out).ok().as_ref().and_then(file_id);
        for i in &self.inputs {
            let how = if out_id.is_some() && out_id == i.file_id {
                Some(if out_canon == i.canonical {
                    "the same file"
                } else {
                    "a hard link to it"
                })
            } else if out_canon.is_some() && out_canon == i.canonical {
                Some("the same path")
            } else if i.is_dir
                && matches!((&out_canon, &i.canonical), (Some(o), Some(d)) if o.starts_with(d))
            {
                Some("a file inside the input folder")
            } else {
                None
            };
            if let Some(how) = how {
                let how = if out_canon != Some(out.to_path_buf())
                    && std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink())
                {
                    "a symlink to it"
                } else {
                    how
                };
                return Err(Error::OutputIsInput {
                    flag: flag.to_string(),
                    out: out.to_path_buf(),
                    input: i.given.clone(),
                    how: how.to_string(),
                });
            }
        }
        Ok(())
    }

    /// Checks `out` and writes `bytes` to it ([`write_output`]).
    pub fn write(&self, flag: &str, out: &Path, bytes: &[u8]) -> Result<()> {
        self.check(flag, out)?;
        write_output(out, bytes)
    }
}

/// `path` made absolute with symlinks resolved; for a file that does not exist yet, its folder's
/// canonical path joined with its name.
fn canonical(p: &Path) -> Option<PathBuf> {
    if let Ok(c) = p.canonicalize() {
        return Some(c);
    }
    let parent = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Some(parent.canonicalize().ok()?.join(p.file_name()?))
}

#[cfg(unix)]
fn file_id(m: &std::fs::Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn file_id(_: &std::fs::Metadata) -> Option<(u64, u64)> {
    None
}

/// A file being written: a temporary file beside the target until [`AtomicFile::commit`] renames it;
/// dropped without a commit, the temporary file is removed.
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    file: Option<File>,
}

impl AtomicFile {
    /// Creates the temporary file for `path` (after removing stale ones of ours for the same name).
    pub fn create(path: &Path) -> Result<AtomicFile> {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        remove_stale_temps(dir, &name);
        let tmp = dir.join(temp_name(&name, std::process::id()));
        let file = File::create(&tmp).map_err(|e| output_error(path, &e))?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            file: Some(file),
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

    /// Syncs the temporary file and renames it onto the target.
    pub fn commit(mut self) -> Result<()> {
        let file = self.file.take().expect("committed once");
        let path = self.path.clone();
        file.sync_all()
            .and_then(|_| std::fs::rename(&self.tmp, &path))
            .map_err(|e| output_error(&path, &e))
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

fn output_error(path: &Path, e: &std::io::Error) -> Error {
    Error::Output {
        path: path.to_path_buf(),
        detail: format!(
            "{}; {}",
            crate::error::io_cause(e),
            crate::error::io_hint(e)
        ),
    }
}

/// `.NAME.PID.tmp`: hidden, ours, and naming the process that writes it.
fn temp_name(name: &str, pid: u32) -> String {
    format!(".{name}.{pid}.tmp")
}

/// Removes `.NAME.PID.tmp` files in `dir` whose process is gone (Linux: no `/proc/PID`; elsewhere:
/// older than a day).
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
        let Some(pid) = n
            .strip_prefix(&prefix)
            .and_then(|r| r.strip_suffix(".tmp"))
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && process_gone(pid, &entry) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

fn process_gone(pid: u32, entry: &std::fs::DirEntry) -> bool {
    if Path::new("/proc/self").exists() {
        return !Path::new("/proc").join(pid.to_string()).exists();
    }
    entry
        .metadata()
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_some_and(|age| age.as_secs() > 24 * 3600)
}

/// Writes `bytes` to `path` (temporary file + rename), or to stdout when `path` is `-`.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<()> {
    if path.as_os_str() == "-" {
        let mut out = std::io::stdout().lock();
        return out
            .write_all(bytes)
            .and_then(|_| out.flush())
            .map_err(|cause| Error::Stdout { cause });
    }
    let mut f = AtomicFile::create(path)?;
    f.file()
        .write_all(bytes)
        .map_err(|e| output_error(path, &e))?;
    f.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_the_input_by_path_symlink_and_hard_link() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.tum");
        std::fs::write(&input, "0 0 0 0 0 0 0 1\n").unwrap();
        let g = OutputGuard::new([&input]);
        assert!(g.check("--json", &input).is_err());
        assert!(g
            .check("--json", &dir.path().join(".").join("in.tum"))
            .is_err());
        #[cfg(unix)]
        {
            let link = dir.path().join("link.tum");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            assert!(g.check("--json", &link).is_err());
            let hard = dir.path().join("hard.tum");
            std::fs::hard_link(&input, &hard).unwrap();
            let e = g.check("--json", &hard).unwrap_err().to_string();
            assert!(e.contains("hard link"), "{e}");
        }
        assert!(g.check("--json", &dir.path().join("out.json")).is_ok());
        assert!(g.check("--json", Path::new("-")).is_ok());
    }

    #[test]
    fn stale_temps_of_dead_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // PIDs above the kernel's maximum (4194304) never run.
        let stale = dir.path().join(temp_name("out.json", 4_194_305));
        std::fs::write(&stale, "half").unwrap();
        let other = dir.path().join(".other.json.4194305.tmp");
        std::fs::write(&other, "not for this output").unwrap();
        write_output(&dir.path().join("out.json"), b"{}").unwrap();
        assert!(!stale.exists());
        assert!(other.exists());
        assert_eq!(std::fs::read(dir.path().join("out.json")).unwrap(), b"{}");
    }
}

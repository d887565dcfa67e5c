//! The output policy: every file trajdrift writes — JSON reports and results, CSV, Markdown, HTML, SVG
//! and PNG figures, MCAP recordings, ROS 1 bags, TUM and CSV exports, summaries — is checked and
//! written here, and nowhere else.
//!
//! **What may be written** ([`OutputGuard`]). A command first names its inputs (recordings, text files,
//! presets, manifests; a rosbag2 recording's `metadata.yaml` names its folder) and then claims every
//! output it will write, before any work. A claim is refused — a usage error, exit 2 — when the output
//!
//! - is an input: the same path after resolving `.`, `..` and symlinks, or a hard link to it;
//! - lies inside an input folder (a rosbag2 folder, a mission folder);
//! - is the path of another output of the same command (`--json X --annotate X`), or a name another
//!   result of the same run will take (a batch mission named `summary`, two estimates whose names map
//!   to one file name: [`names`]).
//!
//! **How it is written** ([`OutputFile`], [`write_output`], [`write_json`]).
//!
//! - `-` and `/dev/stdout` are standard output (`/dev/stderr` standard error).
//! - A target that exists and is not a regular file — a device such as `/dev/null`, a FIFO, a
//!   terminal, a symlink to one of them — is written through: opened and written, never replaced.
//! - A regular file (or a new one) is written into a locked temporary file beside it and renamed onto it
//!   when complete (`atomic`); a symlink to a regular file keeps pointing at it, and the file it
//!   points at is replaced. A failure at any step removes the temporary file and leaves the target as
//!   it was; a run killed outright leaves one that the next writer of the folder removes, recognised
//!   by the lock nobody holds.

pub(crate) mod atomic;
pub mod lock;
pub mod names;

use std::fs::File;
use std::io::Write;
use std::path::{Component, Path, PathBuf};

pub use atomic::{remove_all_stale_temps, remove_stale_temps, AtomicFile};

use crate::error::{Error, Result};

/// One input as the guard compares it.
#[derive(Debug, Clone)]
struct InputId {
    given: PathBuf,
    resolved: PathBuf,
    /// (device, inode) on Unix.
    file_id: Option<(u64, u64)>,
    is_dir: bool,
}

/// One output claimed by the command.
#[derive(Debug, Clone)]
struct Claim {
    flag: String,
    /// `None` for standard output.
    resolved: Option<PathBuf>,
}

/// The inputs of a command and the outputs it has claimed; see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct OutputGuard {
    inputs: Vec<InputId>,
    claims: Vec<Claim>,
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

    /// Adds one input. A rosbag2 recording's `metadata.yaml` also adds its folder: every file in it
    /// is part of the recording. A folder also adds the files that are read through it, wherever
    /// they are (a symlink, a `../` path): the split files its `metadata.yaml` names, or the
    /// recordings of a mission folder.
    pub fn add(&mut self, path: &Path) {
        if is_stdout(path) || path.as_os_str().is_empty() {
            return;
        }
        let meta = std::fs::metadata(path).ok();
        let resolved = resolve(path);
        let is_dir = meta.as_ref().is_some_and(|m| m.is_dir());
        // A folder reached twice (a symlink loop) is expanded once.
        let seen = is_dir
            && self
                .inputs
                .iter()
                .any(|i| i.is_dir && i.resolved == resolved);
        self.inputs.push(InputId {
            given: path.to_path_buf(),
            resolved,
            file_id: meta.as_ref().and_then(file_id),
            is_dir,
        });
        if path.file_name().is_some_and(|n| n == "metadata.yaml") {
            if let Some(dir) = path.parent().filter(|d| d.is_dir()) {
                self.add(dir);
            }
        } else if is_dir && !seen {
            for file in read_through(path) {
                self.add(&file);
            }
        }
    }

    /// Refuses `out` (given with `flag`) when it resolves to an input or lies inside an input folder:
    /// [`Error::OutputIsInput`], a usage error (exit 2). Standard output is always allowed.
    pub fn check(&self, flag: &str, out: &Path) -> Result<()> {
        if is_stdout(out) || is_stderr(out) {
            return Ok(());
        }
        let out_resolved = resolve(out);
        let out_id = std::fs::metadata(out).ok().as_ref().and_then(file_id);
        for i in &self.inputs {
            let how = if out_id.is_some() && out_id == i.file_id {
                if out_resolved == i.resolved {
                    "the same file"
                } else {
                    "a hard link to it"
                }
            } else if out_resolved == i.resolved {
                "the same path"
            } else if i.is_dir && out_resolved.starts_with(&i.resolved) {
                "a file inside the input folder"
            } else {
                continue;
            };
            let how = if std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink())
                && how != "a file inside the input folder"
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
        Ok(())
    }

    /// Claims the file `out` for `flag`: [`OutputGuard::check`], and refused
    /// ([`Error::OutputClash`], exit 2) when another output of the command was claimed at the same
    /// path (two outputs on standard output included).
    pub fn claim(&mut self, flag: &str, out: &Path) -> Result<()> {
        self.claim_as(flag, out)
    }

    /// Claims the folder `dir` for `flag` (`--plot DIR`, a batch's `--out`): not an input, not inside
    /// an input folder, not another output, and a folder or nothing yet (not a file, not a device).
    /// The files written into it are claimed one by one.
    pub fn claim_dir(&mut self, flag: &str, dir: &Path) -> Result<()> {
        if is_stdout(dir) || is_stderr(dir) {
            return Err(Error::InvalidArgument(format!(
                "{flag} takes a folder, not `{}`",
                dir.display()
            )));
        }
        self.claim_as(flag, dir)?;
        match std::fs::metadata(dir) {
            Ok(m) if !m.is_dir() => Err(Error::InvalidArgument(format!(
                "{flag} {}: is {}, expected a folder; pass a new or existing folder",
                dir.display(),
                if m.is_file() {
                    "a file"
                } else {
                    "not a folder (a device, a FIFO)"
                }
            ))),
            _ => Ok(()),
        }
    }

    fn claim_as(&mut self, flag: &str, out: &Path) -> Result<()> {
        self.check(flag, out)?;
        let resolved = (!is_stdout(out)).then(|| resolve(out));
        for c in &self.claims {
            let same = match (&resolved, &c.resolved) {
                (None, None) => true,
                (Some(a), Some(b)) => a == b,
                _ => false,
            };
            if same {
                return Err(Error::OutputClash {
                    flag: flag.to_string(),
                    out: out.to_path_buf(),
                    other: c.flag.clone(),
                });
            }
        }
        self.claims.push(Claim {
            flag: flag.to_string(),
            resolved,
        });
        Ok(())
    }

    /// Checks `out` and writes `bytes` to it ([`write_output`]).
    pub fn write(&self, flag: &str, out: &Path, bytes: &[u8]) -> Result<()> {
        self.check(flag, out)?;
        write_output(out, bytes)
    }
}

/// The files and folders read through the folder `dir`: the split files its `metadata.yaml` names (a
/// rosbag2 folder), or the recordings in it (a mission folder). Nothing when it cannot be read: the
/// command then fails to read it too.
fn read_through(dir: &Path) -> Vec<PathBuf> {
    if dir.join("metadata.yaml").is_file() {
        crate::sources::rosbag2::metadata::read(dir)
            .map(|m| m.relative_file_paths.iter().map(|f| dir.join(f)).collect())
            .unwrap_or_default()
    } else {
        crate::sources::open::recordings_in(dir).unwrap_or_default()
    }
}

/// `p` made absolute, with symlinks resolved in the part of it that exists and `.` and `..` resolved
/// by name in the part that does not (yet).
pub fn resolve(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let abs = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    };
    let parts: Vec<Component<'_>> = abs.components().collect();
    for keep in (1..parts.len()).rev() {
        let head: PathBuf = parts[..keep].iter().collect();
        if let Ok(mut r) = head.canonicalize() {
            for c in &parts[keep..] {
                match c {
                    Component::ParentDir => {
                        r.pop();
                    }
                    Component::Normal(n) => r.push(n),
                    _ => {}
                }
            }
            return r;
        }
    }
    abs
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

/// Whether `path` means standard output: `-`, `/dev/stdout`, `/dev/fd/1`, `/proc/self/fd/1`.
pub fn is_stdout(path: &Path) -> bool {
    matches!(
        path.to_str(),
        Some("-" | "/dev/stdout" | "/dev/fd/1" | "/proc/self/fd/1")
    )
}

/// Whether `path` means standard error: `/dev/stderr`, `/dev/fd/2`, `/proc/self/fd/2`.
pub fn is_stderr(path: &Path) -> bool {
    matches!(
        path.to_str(),
        Some("/dev/stderr" | "/dev/fd/2" | "/proc/self/fd/2")
    )
}

/// A file being written by the policy: a regular file through [`AtomicFile`], anything else (a
/// device, a FIFO) written through. For writers that stream (MCAP, bags); [`write_output`] for bytes.
#[derive(Debug)]
pub struct OutputFile {
    inner: Inner,
}

#[derive(Debug)]
enum Inner {
    Atomic(AtomicFile),
    Through { path: PathBuf, file: File },
}

impl OutputFile {
    /// Opens `path` for writing as the policy says. Standard output cannot be opened this way (MCAP
    /// and bags are written with seeks): give a file, or use [`write_output`].
    pub fn create(path: &Path) -> Result<OutputFile> {
        if is_stdout(path) || is_stderr(path) {
            return Err(Error::Output {
                path: path.to_path_buf(),
                detail: "this output is written with seeks and cannot go to a terminal or a pipe; give a file".into(),
            });
        }
        match target_kind(path)? {
            Kind::Through(target) => {
                let file = std::fs::OpenOptions::new()
                    .write(true)
                    .open(&target)
                    .map_err(|e| Error::output(path, &e))?;
                Ok(OutputFile {
                    inner: Inner::Through {
                        path: path.to_path_buf(),
                        file,
                    },
                })
            }
            Kind::Regular(target) => Ok(OutputFile {
                inner: Inner::Atomic(AtomicFile::create(&target)?),
            }),
        }
    }

    /// The file to write into.
    pub fn file(&mut self) -> &mut File {
        match &mut self.inner {
            Inner::Atomic(a) => a.file(),
            Inner::Through { file, .. } => file,
        }
    }

    /// The path the output was asked for.
    pub fn path(&self) -> &Path {
        match &self.inner {
            Inner::Atomic(a) => a.path(),
            Inner::Through { path, .. } => path,
        }
    }

    /// Completes the output: the rename of a regular file, a flush of anything else.
    pub fn commit(self) -> Result<()> {
        match self.inner {
            Inner::Atomic(a) => a.commit(),
            Inner::Through { path, mut file } => file.flush().map_err(|e| Error::output(&path, &e)),
        }
    }
}

/// What kind of target a path is.
enum Kind {
    /// A regular file, or none yet: written atomically at this path (symlinks followed).
    Regular(PathBuf),
    /// A device, FIFO, terminal or socket: written through at this path.
    Through(PathBuf),
}

fn target_kind(path: &Path) -> Result<Kind> {
    // Follow symlinks by hand so that a link to a file not yet there creates that file, as a shell's
    // `>` does; at most 40 links, as the kernel.
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Err(_) => return Ok(Kind::Regular(p)),
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&p).map_err(|e| Error::output(path, &e))?;
                p = atomic::folder_of(&p).join(target);
            }
            Ok(m) if m.is_dir() => {
                return Err(Error::Output {
                    path: path.to_path_buf(),
                    detail: "is a folder; give a file name".into(),
                })
            }
            Ok(m) if m.is_file() => return Ok(Kind::Regular(p)),
            Ok(_) => return Ok(Kind::Through(p)),
        }
    }
    Err(Error::Output {
        path: path.to_path_buf(),
        detail: "too many levels of symlinks (a loop?); check the path".into(),
    })
}

/// Writes `bytes` to `path` by the policy: standard output or error, written through (a device, a
/// FIFO), or a temporary file renamed onto a regular file.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<()> {
    if is_stdout(path) {
        let mut out = std::io::stdout().lock();
        return out
            .write_all(bytes)
            .and_then(|_| out.flush())
            .map_err(|cause| Error::Stdout { cause });
    }
    if is_stderr(path) {
        let mut err = std::io::stderr().lock();
        return err
            .write_all(bytes)
            .and_then(|_| err.flush())
            .map_err(|e| Error::output(path, &e));
    }
    let mut f = OutputFile::create(path)?;
    f.file()
        .write_all(bytes)
        .map_err(|e| Error::output(path, &e))?;
    f.commit()
}

/// Writes `value` as pretty JSON with a final newline ([`write_output`]): the one JSON writer.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|e| Error::Output {
        path: path.to_path_buf(),
        detail: format!("cannot serialise the JSON: {e}"),
    })?;
    bytes.push(b'\n');
    write_output(path, &bytes)
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
        assert!(g
            .check("--json", &dir.path().join("new/../in.tum"))
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
    fn a_rosbag2_folder_is_an_input_folder() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("bag");
        std::fs::create_dir(&bag).unwrap();
        std::fs::write(bag.join("metadata.yaml"), "").unwrap();
        for input in [bag.clone(), bag.join("metadata.yaml")] {
            let g = OutputGuard::new([&input]);
            let e = g.check("--html", &bag.join("metadata.yaml")).unwrap_err();
            assert!(matches!(e, Error::OutputIsInput { .. }));
            assert!(g.check("--html", &bag.join("new.html")).is_err());
            assert!(g.check("--html", &dir.path().join("r.html")).is_ok());
        }
    }

    #[cfg(unix)]
    #[test]
    fn the_files_read_through_a_folder_are_inputs_wherever_they_are() {
        let dir = tempfile::tempdir().unwrap();
        let (victim, victim2) = (dir.path().join("victim.mcap"), dir.path().join("v2.mcap"));
        std::fs::write(&victim, "mcap").unwrap();
        std::fs::write(&victim2, "mcap").unwrap();
        // A mission folder holding a symlink out of it.
        let mission = dir.path().join("ml");
        std::fs::create_dir(&mission).unwrap();
        std::os::unix::fs::symlink("../v2.mcap", mission.join("a.mcap")).unwrap();
        let g = OutputGuard::new([&mission]);
        assert!(g.check("--json", &victim2).is_err());
        assert!(g.check("--json", &victim).is_ok());
        // A rosbag2 folder whose metadata.yaml names a file outside it.
        let bag = dir.path().join("rb");
        std::fs::create_dir(&bag).unwrap();
        std::fs::write(
            bag.join("metadata.yaml"),
            "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths:\n  - ../victim.mcap\n",
        )
        .unwrap();
        for input in [bag.clone(), bag.join("metadata.yaml")] {
            let g = OutputGuard::new([&input]);
            assert!(g.check("--json", &victim).is_err());
            assert!(g.check("--json", &victim2).is_ok());
        }
        // A mission folder holding that rosbag2 folder, and a loop of folders.
        std::os::unix::fs::symlink("../rb", mission.join("rb")).unwrap();
        std::fs::create_dir(mission.join("loop")).unwrap();
        std::fs::write(
            mission.join("loop/metadata.yaml"),
            "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths:\n  - ..\n",
        )
        .unwrap();
        let g = OutputGuard::new([&mission]);
        assert!(g.check("--json", &victim).is_err());
    }

    #[test]
    fn a_folder_output_that_is_a_file_is_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("ref.tum");
        std::fs::write(&file, "").unwrap();
        let mut g = OutputGuard::default();
        let e = g.claim_dir("--out", &file).unwrap_err();
        assert!(matches!(e, Error::InvalidArgument(_)));
        assert!(
            e.to_string().contains("is a file, expected a folder"),
            "{e}"
        );
        #[cfg(unix)]
        {
            let e = g.claim_dir("--plot", Path::new("/dev/null")).unwrap_err();
            assert!(e.to_string().contains("expected a folder"), "{e}");
        }
        g.claim_dir("--out", dir.path()).unwrap();
        g.claim_dir("--plot", &dir.path().join("new")).unwrap();
    }

    #[test]
    fn two_outputs_on_one_path_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut g = OutputGuard::new(Vec::<PathBuf>::new());
        let x = dir.path().join("x");
        g.claim("--json", &x).unwrap();
        let e = g.claim("--annotate", &dir.path().join("./x")).unwrap_err();
        assert!(e.to_string().contains("--json"), "{e}");
        g.claim("--json", Path::new("-")).unwrap();
        assert!(g.claim("OUT", Path::new("/dev/stdout")).is_err());
        g.claim_dir("--plot", &dir.path().join("figs")).unwrap();
        assert!(g.claim("--html", &dir.path().join("figs")).is_err());
        g.claim("--html", &dir.path().join("figs/r.html")).unwrap();
    }

    #[test]
    fn write_output_replaces_a_regular_file_and_keeps_a_symlink() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("t.json");
        std::fs::write(&target, "old").unwrap();
        write_output(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        #[cfg(unix)]
        {
            let link = dir.path().join("l.json");
            std::os::unix::fs::symlink("t.json", &link).unwrap();
            write_output(&link, b"via link").unwrap();
            assert!(std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink());
            assert_eq!(std::fs::read(&target).unwrap(), b"via link");
            // A device is written through, never replaced.
            write_output(Path::new("/dev/null"), b"x").unwrap();
            assert!(std::fs::metadata("/dev/null")
                .map(|m| !m.is_file())
                .unwrap());
        }
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(!names.iter().any(|n| n.ends_with(".tmp")), "{names:?}");
    }
}

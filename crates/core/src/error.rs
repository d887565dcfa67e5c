//! The library's error type.
//!
//! Every variant renders as one line that names the file, the topic (where there is one) and what the
//! user can do about it: the CLI prints it as is and exits non-zero. No code path in the library
//! panics on bad input; it returns one of these.

use std::path::PathBuf;

/// Result alias used throughout the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong while evaluating a recording.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be opened or read. The cause is said once (it is not also the error's
    /// `source`, so a printed chain does not repeat it), followed by what to do.
    #[error("{path}: cannot read: {}; {}", crate::error::io_cause(.cause), crate::error::io_hint(.cause))]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },

    /// The file is not an MCAP recording (bad magic, or no record could be parsed), nor a ROS 1 bag.
    #[error("{path}: not an MCAP recording nor a ROS 1 bag ({detail}); pass a .mcap or .bag file or a rosbag2 folder (a text trajectory goes with eval's --reference-file/--estimate-file)")]
    NotMcap { path: PathBuf, detail: String },

    /// The MCAP file is damaged beyond what truncation recovery covers.
    #[error("{path}: damaged MCAP ({detail}); try `mcap recover` on it first")]
    CorruptMcap { path: PathBuf, detail: String },

    /// A requested topic is not in the recording.
    #[error("{path}: topic {topic} not found; {}", crate::error::present(.available))]
    TopicNotFound {
        path: PathBuf,
        topic: String,
        available: Vec<String>,
    },

    /// A requested topic has a message type trajdrift cannot read as a trajectory.
    #[error("{path}: topic {topic} has type {type_name}, which trajdrift cannot read as a trajectory; supported types: {}", .supported.join(", "))]
    UnsupportedType {
        path: PathBuf,
        topic: String,
        type_name: String,
        supported: Vec<String>,
    },

    /// A preset's topics for a role are absent from the recording.
    #[error("{path}: preset {preset}: no {what} topic ({topics} not present); {hint}")]
    PresetTopicMissing {
        path: PathBuf,
        preset: String,
        what: String,
        topics: String,
        hint: String,
    },

    /// A message could not be decoded.
    #[error("{path}: topic {topic}: cannot decode message {index}: {detail}; the message is damaged, or the channel's schema does not match its messages")]
    Decode {
        path: PathBuf,
        topic: String,
        index: u64,
        detail: String,
    },

    /// A text trajectory file could not be parsed.
    #[error("{path}:{line}: {detail}; expected TUM lines `t x y z qx qy qz qw`")]
    TextFormat {
        path: PathBuf,
        line: usize,
        detail: String,
    },

    /// A trajectory has too few usable samples for the requested computation.
    #[error("{what}: only {n} usable samples (need at least {need}); check the topic or file, the crop (--t-start/--t-end) and the stamps")]
    TooFewSamples { what: String, n: usize, need: usize },

    /// The estimate and the reference do not overlap in time.
    #[error("{estimate} [{est_start:.3}, {est_end:.3}] s and the reference [{ref_start:.3}, {ref_end:.3}] s do not overlap in time (after a shift of {offset:.3} s); check --stamp, --time-offset and --max-offset")]
    NoOverlap {
        estimate: String,
        est_start: f64,
        est_end: f64,
        ref_start: f64,
        ref_end: f64,
        offset: f64,
    },

    /// A command-line or manifest value is invalid.
    #[error("{0}")]
    InvalidArgument(String),

    /// A standard metric (APE, RPE) cannot be computed on these data (no associated pairs, a degenerate
    /// alignment, a relation that needs orientation): the message says what to do.
    #[error("{0}")]
    Metric(String),

    /// Writing an output failed.
    #[error("{path}: cannot write: {detail}")]
    Output { path: PathBuf, detail: String },

    /// An output resolves to one of the inputs (same path, a symlink to it, or a hard link).
    #[error("{flag} {out}: is the input {input} ({how}); writing it would destroy the input, choose another output file")]
    OutputIsInput {
        flag: String,
        out: PathBuf,
        input: PathBuf,
        how: String,
    },

    /// Two outputs of one command (or one run) would be the same file.
    #[error("{flag} {out}: {other} writes the same file; give each output its own path")]
    OutputClash {
        flag: String,
        out: PathBuf,
        other: String,
    },

    /// An output folder is being written by another trajdrift run.
    #[error("{path}: another trajdrift {what} is writing into this folder ({holder}); wait for it to finish, or choose another --out")]
    OutputBusy {
        path: PathBuf,
        what: String,
        holder: String,
    },

    /// Standard output could not be written.
    #[error("<stdout>: cannot write: {}", crate::error::io_cause(.cause))]
    Stdout { cause: std::io::Error },

    /// A recording is damaged at a known place: the file, the byte offset and what was wrong there.
    #[error("{path}: damaged at byte {offset}: {detail}; the file is not a valid recording from there on (repair a copy, e.g. `mcap recover` or `rosbag reindex`)")]
    Damaged {
        path: PathBuf,
        offset: u64,
        detail: String,
    },

    /// A ROS 1 bag is damaged or not a version 2.0 bag.
    #[error("{path}: cannot read ROS 1 bag ({detail}); check it with `rosbag info`, or `rosbag reindex` a copy")]
    CorruptBag { path: PathBuf, detail: String },

    /// A ROS 1 bag chunk uses a compression trajdrift does not read.
    #[error("{path}: ROS 1 bag chunk at byte {offset} uses compression `{compression}` (supported: none, bz2, lz4); run `rosbag decompress` on a copy first")]
    UnsupportedCompression {
        path: PathBuf,
        offset: u64,
        compression: String,
    },

    /// A rosbag2 folder cannot be read (metadata.yaml, its files, or the sqlite3 database).
    #[error("{path}: rosbag2 folder: {detail}")]
    Rosbag2 { path: PathBuf, detail: String },
    /// A TF chain (`/tf:PARENT:CHILD`) or a `tf-static:` lever cannot be built from the recording's
    /// `/tf` and `/tf_static` edges.
    #[error("{path}: {topic}: {detail}; run `trajdrift topics {path}` to list the TF frame pairs")]
    TfChain {
        path: PathBuf,
        topic: String,
        detail: String,
    },

    /// A text trajectory file (KITTI, EuRoC, CSV) could not be parsed; `hint` says what was expected.
    #[error("{path}:{line}: {detail}; {hint}")]
    Text {
        path: PathBuf,
        line: usize,
        detail: String,
        hint: String,
    },

    /// The recordings of a mission (several files, or a mission folder) do not fit together.
    #[error("{path}: {detail}")]
    Mission { path: PathBuf, detail: String },
}

impl Error {
    /// Builds an [`Error::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            cause,
        }
    }

    /// Builds an [`Error::Output`] for `path` from an I/O error: its cause, and what to do about it.
    pub fn output(path: impl Into<PathBuf>, cause: &std::io::Error) -> Self {
        Error::Output {
            path: path.into(),
            detail: format!("{}; {}", io_cause(cause), io_hint(cause)),
        }
    }

    /// The exit status this error ends the process with: usage errors (a flag's value, an output
    /// that would overwrite an input) are [`ExitStatus::Usage`], everything else a failure.
    pub fn exit_status(&self) -> ExitStatus {
        match self {
            Error::InvalidArgument(_)
            | Error::OutputIsInput { .. }
            | Error::OutputClash { .. }
            | Error::OutputBusy { .. } => ExitStatus::Usage,
            _ => ExitStatus::Failure,
        }
    }

    /// Whether this is a write to a closed standard output (`trajdrift … | head`): the reader has
    /// what it wanted, so the process ends quietly, like ripgrep.
    pub fn is_broken_pipe(&self) -> bool {
        matches!(self, Error::Io { cause, .. } | Error::Stdout { cause }
            if cause.kind() == std::io::ErrorKind::BrokenPipe)
    }
}

/// How a command ended; the one exit-code type. The library returns it, the binary maps it to the
/// process's exit code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExitStatus {
    /// Everything went fine (0).
    Ok = 0,
    /// The command failed: bad or damaged input, an I/O error (1).
    Failure = 1,
    /// The command line or a parameter value is wrong (2).
    Usage = 2,
    /// The command finished, with a warning the user must see (truncated recording, weak offset) (3).
    Warning = 3,
}

impl ExitStatus {
    /// The process exit code.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// [`ExitStatus::Warning`] when there is at least one warning, else [`ExitStatus::Ok`].
    pub fn from_warnings(any: bool) -> Self {
        if any {
            ExitStatus::Warning
        } else {
            ExitStatus::Ok
        }
    }
}

/// The topics a recording holds, for "not found" messages; says when there is none.
pub fn present(available: &[String]) -> String {
    if available.is_empty() {
        "the recording holds no topic at all (it is empty or damaged; run `trajdrift topics` on it)"
            .into()
    } else {
        format!("topics present: {}", available.join(", "))
    }
}

/// An I/O error's message without the `(os error N)` suffix std adds.
pub fn io_cause(e: &std::io::Error) -> String {
    let s = e.to_string();
    match s.rfind(" (os error ") {
        Some(i) if s.ends_with(')') => s[..i].to_string(),
        _ => s,
    }
}

/// What to do about an I/O error, by its cause: the common ones each get their own advice.
pub fn io_hint(e: &std::io::Error) -> &'static str {
    use std::io::ErrorKind as K;
    #[cfg(unix)]
    match e.raw_os_error() {
        Some(libc::ENAMETOOLONG) => {
            return "the name is longer than the file system allows (255 bytes a name on most): choose a shorter file or folder name"
        }
        Some(libc::EROFS) => {
            return "the file system is read-only (a mounted image, a read-only share): write to another folder"
        }
        Some(libc::EBUSY) => {
            return "the file is busy (in use by another program, or a mount point): close what holds it or choose another name"
        }
        Some(libc::ETXTBSY) => {
            return "the file is a program being run: choose another name"
        }
        Some(libc::ENOTDIR) => {
            return "a part of the path is a file, not a folder: check the path"
        }
        Some(libc::ENOSPC) => {
            return "the disk is full: free some space, or write to another disk"
        }
        Some(libc::EDQUOT) => {
            return "your disk quota is used up: free some space, or write to another disk"
        }
        Some(libc::EMFILE | libc::ENFILE) => {
            return "too many open files: raise the limit (`ulimit -n`) or run fewer jobs at once"
        }
        Some(libc::ELOOP) => return "too many levels of symlinks (a loop?): check the links",
        Some(libc::EXDEV) => return "the rename crosses file systems: write to a folder on one file system",
        Some(libc::EFBIG) => return "the file is larger than the file system allows: write to another file system",
        _ => {}
    }
    match e.kind() {
        K::NotFound => "check the path (run `ls` on it)",
        K::PermissionDenied => "check the permissions of the file and of its folder",
        K::IsADirectory => "pass a file, not a folder",
        K::UnexpectedEof => "the file ends early: it may be truncated or still being written",
        K::StorageFull => "free some disk space",
        K::InvalidData => "its content is not what was expected (not UTF-8 text?): check that it is the file you meant",
        K::AlreadyExists => "a file of that name appeared meanwhile: try again",
        K::TimedOut => "start the program that writes into it first, or pass a regular file",
        _ => "check that the file is readable and the disk is healthy",
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn each_common_cause_has_its_own_advice() {
        let generic = io_hint(&std::io::Error::other("x"));
        for (code, says) in [
            (libc::ENAMETOOLONG, "longer than the file system allows"),
            (libc::EROFS, "read-only"),
            (libc::EBUSY, "busy"),
            (libc::ENOTDIR, "not a folder"),
            (libc::ENOSPC, "disk is full"),
            (libc::EDQUOT, "quota"),
        ] {
            let hint = io_hint(&std::io::Error::from_raw_os_error(code));
            assert!(hint.contains(says), "{code}: {hint}");
            assert_ne!(hint, generic);
        }
    }
}

//! Advisory locks (`flock(2)`): held by a writer on its temporary file, and by a batch on its output
//! folder. The kernel releases them when the process ends however it ends, so a lock nobody holds
//! means nobody is writing. Hand-written over `libc::flock` (a few lines; the standard library's
//! `File::lock` is newer than the project's minimum Rust version).
//!
//! Elsewhere than Unix the locks are no-ops: a stale temporary file is then recognised by its age.

use std::fs::File;
use std::path::Path;

/// Blocks until `file` is locked exclusively.
pub fn exclusive(file: &File) -> std::io::Result<()> {
    imp::flock(file, imp::EXCLUSIVE, true).map(|_| ())
}

/// Locks `file` exclusively if nobody holds a lock on it; `Ok(false)` when someone does.
pub fn try_exclusive(file: &File) -> std::io::Result<bool> {
    imp::flock(file, imp::EXCLUSIVE, false)
}

/// Locks `file` shared (with other shared holders) if nobody holds it exclusively; `Ok(false)`
/// otherwise.
pub fn try_shared(file: &File) -> std::io::Result<bool> {
    imp::flock(file, imp::SHARED, false)
}

/// Whether `path` still names `file` (same device and inode): a file removed or replaced after it
/// was opened does not.
pub fn names_file(path: &Path, file: &File) -> bool {
    imp::same_file(path, file)
}

#[cfg(unix)]
mod imp {
    use std::fs::File;
    use std::os::unix::fs::MetadataExt;
    use std::os::unix::io::AsRawFd;
    use std::path::Path;

    pub const EXCLUSIVE: i32 = libc::LOCK_EX;
    pub const SHARED: i32 = libc::LOCK_SH;

    pub fn flock(file: &File, how: i32, wait: bool) -> std::io::Result<bool> {
        let op = if wait { how } else { how | libc::LOCK_NB };
        loop {
            // SAFETY: flock on a file descriptor we own; no memory is passed.
            if unsafe { libc::flock(file.as_raw_fd(), op) } == 0 {
                return Ok(true);
            }
            let e = std::io::Error::last_os_error();
            match e.raw_os_error() {
                Some(libc::EINTR) => continue,
                Some(libc::EWOULDBLOCK) if !wait => return Ok(false),
                _ => return Err(e),
            }
        }
    }

    pub fn same_file(path: &Path, file: &File) -> bool {
        match (std::fs::symlink_metadata(path), file.metadata()) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
}

#[cfg(not(unix))]
mod imp {
    use std::fs::File;
    use std::path::Path;

    pub const EXCLUSIVE: i32 = 2;
    pub const SHARED: i32 = 1;

    /// No advisory locks here: a stale file is one older than a day.
    pub fn flock(file: &File, _how: i32, wait: bool) -> std::io::Result<bool> {
        if wait {
            return Ok(true);
        }
        let old = file
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age.as_secs() > 24 * 3600);
        Ok(old)
    }

    pub fn same_file(path: &Path, _file: &File) -> bool {
        path.exists()
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn a_second_holder_is_refused_until_the_first_closes() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l");
        std::fs::write(&p, "").unwrap();
        let a = File::open(&p).unwrap();
        let b = File::open(&p).unwrap();
        assert!(try_exclusive(&a).unwrap());
        assert!(!try_exclusive(&b).unwrap());
        assert!(!try_shared(&b).unwrap());
        drop(a);
        assert!(try_shared(&b).unwrap());
        let c = File::open(&p).unwrap();
        assert!(try_shared(&c).unwrap());
        assert!(!try_exclusive(&File::open(&p).unwrap()).unwrap());
        assert!(names_file(&p, &c));
        std::fs::remove_file(&p).unwrap();
        assert!(!names_file(&p, &c));
    }
}

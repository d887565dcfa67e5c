//! How an input file is opened, and how much of it may be read.
//!
//! **Streams.** A path that is not a regular file — a FIFO, a shell's process substitution
//! (`export <(cat x.tum) out.tum` passes `/dev/fd/63`, a pipe), a character device — can be read only
//! once, and the text readers open their file several times (format detection, the header, the rows).
//! Such an input is read once, as it arrives, into an unnamed temporary file (memory stays flat) and
//! every later open reads that copy: no pose is lost. A FIFO nobody writes into is not waited on for
//! ever: when no writer appears within [`NO_WRITER_WAIT`] the read fails and says so; a writer that is
//! there but slow (a conversion feeding a process substitution) is waited for. Recordings are read with
//! seeks and are refused as streams ([`require_seekable`]).
//!
//! **Bounds.** Every read has a size bound and says so when it is passed: a line of text is at most
//! [`MAX_LINE_BYTES`] (a file without newlines ends with a clear error, not with the buffer doubling
//! until memory runs out), a stream at most [`MAX_STREAM_BYTES`], and whole-file reads (manifests,
//! presets, JSON results, `metadata.yaml`) their caller's bound ([`read_bounded`]).

use std::collections::HashMap;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

use crate::error::{Error, Result};

/// The longest line a text trajectory may have: a TUM or KITTI row is under 300 bytes, a wide CSV
/// row a few kilobytes.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The most a stream (FIFO, pipe, device) input is read: 4 GiB, a text trajectory of tens of
/// millions of poses.
pub const MAX_STREAM_BYTES: u64 = 4 << 30;

/// How long a FIFO is given for a writer to appear.
pub const NO_WRITER_WAIT: Duration = Duration::from_secs(5);

/// Whether `path` exists and is neither a regular file nor a folder (symlinks followed).
pub fn is_stream(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// What kind of non-regular file `path` is, for messages.
pub fn stream_kind(path: &Path) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if let Ok(m) = std::fs::metadata(path) {
            let t = m.file_type();
            if t.is_fifo() {
                return "a pipe or FIFO";
            }
            if t.is_char_device() {
                return "a character device";
            }
            if t.is_block_device() {
                return "a block device";
            }
            if t.is_socket() {
                return "a socket";
            }
        }
    }
    "not a regular file"
}

/// Refuses a stream where a regular file is needed (a recording, read with seeks and several times).
pub fn require_seekable(path: &Path, what: &str) -> Result<()> {
    if is_stream(path) {
        return Err(Error::InvalidArgument(format!(
            "{}: is {}; {what} is read with seeks, more than once: save it to a file first",
            path.display(),
            stream_kind(path)
        )));
    }
    Ok(())
}

/// Opens a text input for reading: a regular file directly, a stream through its one-time copy;
/// either way every line is bounded by [`MAX_LINE_BYTES`].
pub fn open_text(path: &Path) -> Result<TextReader> {
    let inner = if is_stream(path) {
        let s = spooled(path, MAX_STREAM_BYTES, true)?;
        if s.len > MAX_STREAM_BYTES {
            return Err(Error::InvalidArgument(format!(
                "{}: {} gave more than {}; save the data to a file and pass the file",
                path.display(),
                stream_kind(path),
                human(MAX_STREAM_BYTES)
            )));
        }
        Inner::Spooled(s, 0)
    } else {
        Inner::File(File::open(path).map_err(|e| Error::io(path, e))?)
    };
    Ok(TextReader {
        inner,
        line: 0,
        line_number: 1,
    })
}

/// A text input's bytes, every line at most [`MAX_LINE_BYTES`] long (a longer one is an
/// `InvalidData` error naming the line).
pub struct TextReader {
    inner: Inner,
    /// Bytes since the last newline.
    line: usize,
    line_number: usize,
}

enum Inner {
    File(File),
    Spooled(Arc<Spool>, u64),
}

impl Read for TextReader {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = match &mut self.inner {
            Inner::File(f) => f.read(buf)?,
            Inner::Spooled(s, pos) => {
                let n = s.read_at(buf, *pos)?;
                *pos += n as u64;
                n
            }
        };
        for &b in &buf[..n] {
            if b == b'\n' {
                self.line = 0;
                self.line_number += 1;
            } else {
                self.line += 1;
                if self.line > MAX_LINE_BYTES {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        format!(
                            "line {} is longer than {} MiB: not a text trajectory (a binary file?)",
                            self.line_number,
                            MAX_LINE_BYTES >> 20
                        ),
                    ));
                }
            }
        }
        Ok(n)
    }
}

/// Reads the whole of `path` (a file or a stream), refused when it holds more than `limit` bytes;
/// `what` names it in the message (`manifest`, `preset`, `mission result`).
pub fn read_bounded(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>> {
    let too_big = || {
        Error::InvalidArgument(format!(
            "{}: larger than {}, more than a {what} can be; check that it is the file you meant",
            path.display(),
            human(limit)
        ))
    };
    if is_stream(path) {
        let s = spooled(path, limit, false)?;
        if s.len > limit {
            return Err(too_big());
        }
        let mut v = vec![0u8; s.len as usize];
        let mut at = 0usize;
        while at < v.len() {
            let n = s
                .read_at(&mut v[at..], at as u64)
                .map_err(|e| Error::io(path, e))?;
            if n == 0 {
                break;
            }
            at += n;
        }
        v.truncate(at);
        return Ok(v);
    }
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    match file.metadata() {
        Ok(m) if m.is_dir() => {
            return Err(Error::io(
                path,
                std::io::Error::from(std::io::ErrorKind::IsADirectory),
            ))
        }
        // Refused by its size, before a byte is read.
        Ok(m) if m.len() > limit => return Err(too_big()),
        _ => {}
    }
    let mut v = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut v)
        .map_err(|e| Error::io(path, e))?;
    if v.len() as u64 > limit {
        return Err(too_big());
    }
    Ok(v)
}

/// [`read_bounded`] as UTF-8 text.
pub fn read_text_bounded(path: &Path, limit: u64, what: &str) -> Result<String> {
    String::from_utf8(read_bounded(path, limit, what)?).map_err(|_| {
        Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"),
        )
    })
}

fn human(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{} GiB", bytes >> 30)
    } else if bytes >= 1 << 20 {
        format!("{} MiB", bytes >> 20)
    } else if bytes >= 1 << 10 {
        format!("{} KiB", bytes >> 10)
    } else {
        format!("{bytes} bytes")
    }
}

/// A stream's one-time copy.
struct Spool {
    file: File,
    len: u64,
}

impl Spool {
    fn read_at(&self, buf: &mut [u8], pos: u64) -> std::io::Result<usize> {
        if pos >= self.len {
            return Ok(0);
        }
        let want = buf.len().min((self.len - pos) as usize);
        read_at(&self.file, &mut buf[..want], pos)
    }
}

#[cfg(unix)]
fn read_at(file: &File, buf: &mut [u8], pos: u64) -> std::io::Result<usize> {
    std::os::unix::fs::FileExt::read_at(file, buf, pos)
}

#[cfg(windows)]
fn read_at(file: &File, buf: &mut [u8], pos: u64) -> std::io::Result<usize> {
    std::os::windows::fs::FileExt::seek_read(file, buf, pos)
}

/// Streams read so far in this process, by the path given.
fn spools() -> &'static Mutex<HashMap<PathBuf, Arc<Spool>>> {
    static SPOOLS: OnceLock<Mutex<HashMap<PathBuf, Arc<Spool>>>> = OnceLock::new();
    SPOOLS.get_or_init(Default::default)
}

/// The copy of the stream at `path`, read now if it was not yet.
fn spooled(path: &Path, limit: u64, text: bool) -> Result<Arc<Spool>> {
    let mut map = spools().lock().unwrap_or_else(|p| p.into_inner());
    if let Some(s) = map.get(path) {
        return Ok(s.clone());
    }
    let s = Arc::new(spool(path, limit, text)?);
    map.insert(path.to_path_buf(), s.clone());
    Ok(s)
}

/// An unnamed temporary file (created and unlinked at once, so nothing is left behind).
fn anonymous_file() -> std::io::Result<File> {
    let dir = std::env::temp_dir();
    for i in 0..16u32 {
        let p = dir.join(format!(".trajdrift-stream-{}-{i}", std::process::id()));
        match std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&p)
        {
            Ok(f) => {
                let _ = std::fs::remove_file(&p);
                return Ok(f);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::from(std::io::ErrorKind::AlreadyExists))
}

/// Reads the stream into its copy, stopping after `limit + 1` bytes (the caller says what is too
/// much); `text`: a line longer than [`MAX_LINE_BYTES`] ends the read with an error (an endless
/// stream without newlines, `/dev/zero`, is not copied to the disk).
fn spool(path: &Path, limit: u64, text: bool) -> Result<Spool> {
    use std::io::Write;
    let mut source = open_stream(path)?;
    let mut file = anonymous_file().map_err(|e| {
        Error::io(
            std::env::temp_dir(),
            std::io::Error::new(
                e.kind(),
                format!("cannot keep a copy of the stream {}: {e}", path.display()),
            ),
        )
    })?;
    let mut buf = vec![0u8; 1 << 16];
    let mut len = 0u64;
    let (mut line, mut line_number) = (0usize, 1usize);
    while len <= limit {
        let want = buf.len().min((limit + 1 - len) as usize);
        let n = source
            .read(&mut buf[..want])
            .map_err(|e| Error::io(path, e))?;
        if n == 0 {
            break;
        }
        if text {
            for &b in &buf[..n] {
                if b == b'\n' {
                    line = 0;
                    line_number += 1;
                } else {
                    line += 1;
                }
            }
            if line > MAX_LINE_BYTES {
                return Err(Error::io(
                    path,
                    std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        format!(
                            "line {line_number} is longer than {} MiB: not a text trajectory (a binary file?)",
                            MAX_LINE_BYTES >> 20
                        ),
                    ),
                ));
            }
        }
        len += n as u64;
        file.write_all(&buf[..n])
            .map_err(|e| Error::io(std::env::temp_dir(), e))?;
    }
    file.flush().map_err(|e| Error::io(path, e))?;
    Ok(Spool { file, len })
}

/// Opens a stream for reading without blocking on a FIFO that has no writer.
#[cfg(unix)]
fn open_stream(path: &Path) -> Result<Box<dyn Read>> {
    use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
    let fifo = std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo());
    if !fifo {
        return Ok(Box::new(File::open(path).map_err(|e| Error::io(path, e))?));
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| Error::io(path, e))?;
    Ok(Box::new(Fifo {
        file,
        path: path.to_path_buf(),
        writer_seen: false,
        waited: Duration::ZERO,
    }))
}

#[cfg(not(unix))]
fn open_stream(path: &Path) -> Result<Box<dyn Read>> {
    Ok(Box::new(File::open(path).map_err(|e| Error::io(path, e))?))
}

/// A FIFO opened without blocking: a read that finds no data waits for it while a writer is there,
/// and ends (EOF) once the writer is gone; if no writer ever appears within [`NO_WRITER_WAIT`], the
/// read fails.
#[cfg(unix)]
struct Fifo {
    file: File,
    path: PathBuf,
    writer_seen: bool,
    waited: Duration,
}

#[cfg(unix)]
impl Read for Fifo {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use std::os::unix::io::AsRawFd;
        let step = Duration::from_millis(20);
        loop {
            match self.file.read(buf) {
                Ok(0) if self.writer_seen => return Ok(0),
                Ok(0) => {
                    // No writer has opened the FIFO yet (Linux reads 0 then, not EAGAIN).
                    if self.waited >= NO_WRITER_WAIT {
                        return Err(std::io::Error::new(
                            std::io::ErrorKind::TimedOut,
                            format!(
                                "nothing was written into the FIFO {} within {} s (no writer?)",
                                self.path.display(),
                                NO_WRITER_WAIT.as_secs()
                            ),
                        ));
                    }
                    std::thread::sleep(step);
                    self.waited += step;
                }
                Ok(n) => {
                    self.writer_seen = true;
                    return Ok(n);
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    // A writer is there, with nothing written yet: wait for data or its end.
                    self.writer_seen = true;
                    let mut p = libc::pollfd {
                        fd: self.file.as_raw_fd(),
                        events: libc::POLLIN,
                        revents: 0,
                    };
                    // SAFETY: one pollfd on a descriptor we own.
                    unsafe { libc::poll(&mut p, 1, 1000) };
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn long_lines_and_big_files_are_bounded() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x");
        std::fs::write(&p, vec![b'1'; MAX_LINE_BYTES + 10]).unwrap();
        let mut s = String::new();
        let e = open_text(&p).unwrap().read_to_string(&mut s).unwrap_err();
        assert!(e.to_string().contains("line 1 is longer than 1 MiB"), "{e}");
        let e = read_bounded(&p, 1000, "manifest").unwrap_err();
        assert!(e.to_string().contains("larger than 1000 bytes"), "{e}");
        assert_eq!(
            read_bounded(&p, 2 << 20, "x").unwrap().len(),
            MAX_LINE_BYTES + 10
        );
    }

    #[test]
    fn a_fifo_is_read_once_and_opened_many_times() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("fifo");
        let c = std::ffi::CString::new(p.to_str().unwrap()).unwrap();
        // SAFETY: a path we own.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let writer = {
            let p = p.clone();
            std::thread::spawn(move || std::fs::write(p, "1 0 0 0\n2 1 0 0\n").unwrap())
        };
        for _ in 0..3 {
            let mut s = String::new();
            open_text(&p).unwrap().read_to_string(&mut s).unwrap();
            assert_eq!(s, "1 0 0 0\n2 1 0 0\n");
        }
        writer.join().unwrap();
        assert!(require_seekable(&p, "a recording").is_err());
    }

    #[test]
    fn a_fifo_without_a_writer_is_not_waited_on_for_ever() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("lonely");
        let c = std::ffi::CString::new(p.to_str().unwrap()).unwrap();
        // SAFETY: a path we own.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let start = std::time::Instant::now();
        let e = read_bounded(&p, 1000, "preset").unwrap_err().to_string();
        assert!(e.contains("no writer"), "{e}");
        assert!(start.elapsed() < NO_WRITER_WAIT + Duration::from_secs(3));
    }
}

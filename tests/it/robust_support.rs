//! Helpers of the robustness tests (`outputs`, `batch_integrity`, `bounds`, `names`): running the
//! binary, a small mission in a temporary folder, and a snapshot of every input's bytes so each test
//! can show that nothing it read was changed.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::hostile_support::small_mcap;

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
}

pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run trajdrift")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Asserts the exit code, with the command and its stderr in the failure.
#[track_caller]
pub fn expect_code(o: &Output, codes: &[i32], what: &str) {
    assert!(
        o.status.code().is_some_and(|c| codes.contains(&c)),
        "{what}: exit {:?}, expected {codes:?}; stderr: {}",
        o.status,
        stderr(o)
    );
}

/// The bytes of every file under some paths (folders walked, symlinks not followed), to show after a
/// test that no input changed.
#[derive(Debug, PartialEq)]
pub struct Snapshot(BTreeMap<PathBuf, Vec<u8>>);

impl Snapshot {
    pub fn of(paths: &[&Path]) -> Snapshot {
        let mut m = BTreeMap::new();
        for p in paths {
            walk(p, &mut m);
        }
        Snapshot(m)
    }

    /// Asserts every file is still there with the same bytes.
    #[track_caller]
    pub fn assert_unchanged(&self) {
        for (p, bytes) in &self.0 {
            let now =
                std::fs::read(p).unwrap_or_else(|e| panic!("input {} gone: {e}", p.display()));
            assert!(now == *bytes, "input {} changed", p.display());
        }
    }
}

fn walk(p: &Path, m: &mut BTreeMap<PathBuf, Vec<u8>>) {
    let Ok(meta) = std::fs::symlink_metadata(p) else {
        return;
    };
    if meta.is_dir() {
        for e in std::fs::read_dir(p).unwrap() {
            walk(&e.unwrap().path(), m);
        }
    } else if meta.is_file() {
        m.insert(p.to_path_buf(), std::fs::read(p).unwrap());
    }
}

/// A temporary folder with a small MCAP (`in.mcap`, 400 samples a trajectory) and its two
/// trajectories as TUM text (`ref.tum`, `est.tum`).
pub struct Fixture {
    pub dir: tempfile::TempDir,
}

impl Fixture {
    pub fn new() -> Fixture {
        let dir = tempfile::tempdir().unwrap();
        small_mcap(&dir.path().join("in.mcap"), 400);
        let f = Fixture { dir };
        for (topic, name) in [
            ("/reference/position", "ref.tum"),
            ("/estimate/odom", "est.tum"),
        ] {
            let o = run(&[
                "export",
                s(&f.p("in.mcap")),
                "--topic",
                topic,
                s(&f.p(name)),
            ]);
            expect_code(&o, &[0], "export");
        }
        f
    }

    pub fn p(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// The names in the folder (hidden ones too), sorted.
    pub fn names(&self, sub: &str) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(self.p(sub))
            .map(|d| {
                d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    }
}

/// `eval` of the fixture's MCAP with a given offset (fast), plus `extra`.
pub fn eval_args<'a>(rec: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "eval",
        rec,
        "--reference",
        "/reference/position",
        "--estimate",
        "/estimate/odom",
        "--time-offset",
        "0.2",
        "-q",
    ];
    v.extend_from_slice(extra);
    v
}

/// Creates a FIFO.
pub fn mkfifo(p: &Path) {
    let c = std::ffi::CString::new(p.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path we own.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

//! Which missions a folder holds (`trajdrift batch FOLDER`): recordings as trajdrift opens them, found
//! the way datasets are laid out.
//!
//! Directly in the folder, each `*.mcap` and `*.bag` file and each rosbag2 folder (one holding
//! `metadata.yaml`) is a mission. One level down, a subfolder holding ROS 1 bags is a **mission
//! folder**: all its recordings are one mission (GrandTour ships a mission as one bag per sensor
//! group), named after the subfolder. A subfolder of MCAP files and rosbag2 folders only holds one
//! mission per recording, named `<subfolder>-<name>` (how runs of MCAP recordings are kept). Hidden
//! entries (a `.name.tmp` being written) are skipped, and a folder reached twice (a symlink to the
//! folder itself, a loop) is walked once. Names keep letters, digits, `.`, `_`, `-`.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::sources::open::is_recording_entry;

/// One mission found: its name and the path `eval` opens (a file, a rosbag2 folder or a mission
/// folder).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FoundMission {
    pub name: String,
    pub recording: PathBuf,
}

/// The missions in `dir`, sorted by name.
pub fn missions_in(dir: &Path) -> Result<Vec<FoundMission>> {
    let mut out = Vec::new();
    // Each folder is walked once: a symlink to the folder itself or to a sibling (a loop, or a
    // second name) adds nothing.
    let mut seen: Vec<PathBuf> = dir.canonicalize().into_iter().collect();
    for p in entries(dir)? {
        if is_recording_entry(&p) {
            out.push(found(dir, &p));
        } else if p.is_dir() {
            let Ok(real) = p.canonicalize() else {
                continue;
            };
            if seen.contains(&real) {
                continue;
            }
            seen.push(real);
            let inner: Vec<PathBuf> = entries(&p)?
                .into_iter()
                .filter(|q| is_recording_entry(q))
                .collect();
            let has_bags = inner.iter().any(|q| is_bag(q));
            if has_bags {
                out.push(found(dir, &p));
            } else {
                out.extend(inner.iter().map(|q| found(dir, q)));
            }
        }
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

fn entries(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let p = e.map_err(|e| Error::io(dir, e))?.path();
        if !p
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        {
            v.push(p);
        }
    }
    v.sort();
    Ok(v)
}

fn is_bag(p: &Path) -> bool {
    p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bag"))
}

/// A mission named by its path under `dir`, without a file's extension, `/` written `-`.
fn found(dir: &Path, p: &Path) -> FoundMission {
    let rel = p.strip_prefix(dir).unwrap_or(p);
    let rel = if p.is_file() {
        rel.with_extension("")
    } else {
        rel.to_path_buf()
    };
    let name = rel
        .to_string_lossy()
        .chars()
        .map(|c| match c {
            '/' | '\\' => '-',
            c if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') => c,
            _ => '_',
        })
        .collect();
    FoundMission {
        name,
        recording: p.to_path_buf(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_rosbag2_folders_and_mission_folders() {
        let d = tempfile::tempdir().unwrap();
        let touch = |p: &str| {
            let p = d.path().join(p);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, b"").unwrap();
        };
        touch("a.mcap");
        touch("b.bag");
        touch("notes.txt");
        touch(".c.mcap.tmp");
        touch("r2/metadata.yaml");
        touch("r2/r2.db3");
        touch("gt/2024_dlio.bag");
        touch("gt/2024_tf_minimal.bag");
        touch("runs/x.mcap");
        touch("runs/y.mcap");
        touch("empty/readme.md");
        let names: Vec<String> = missions_in(d.path())
            .unwrap()
            .into_iter()
            .map(|m| m.name)
            .collect();
        assert_eq!(names, ["a", "b", "gt", "r2", "runs-x", "runs-y"]);
        let gt = missions_in(d.path()).unwrap();
        assert_eq!(gt[2].recording, d.path().join("gt"));
    }
}

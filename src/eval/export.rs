//! `--export-aligned`: writes each estimate as the Drift Error saw it — moved onto the reference clock
//! by the report's clock correction ([`crate::clock`]; and cropped like the reference) — as a TUM
//! file, so that evo (or any TUM tool) can compare it with the reference without redoing the time
//! alignment.
//!
//! With one estimate the file is written as given. With several, the estimate's name is inserted before
//! the extension: `aligned.tum` → `aligned.lio.tum`, `aligned.odom.tum`, the name mapped to a file name
//! by the one mapping ([`crate::output::names::file_stem`]: `estimate/odom` gives
//! `aligned.estimate_odom.tum`; two names mapping to one file are refused before the evaluation).
//! Written via a temporary file and a rename ([`crate::output::write_output`]).

use std::path::{Path, PathBuf};

use crate::error::Result;
use crate::output::write_output;
use crate::sources::tum::write_tum;
use crate::trajectory::Trajectory;

/// The file one estimate is exported to: `file` itself when there is one estimate, else `file` with
/// `.NAME` inserted before its extension.
pub fn aligned_path(file: &Path, name: &str, n_estimates: usize) -> PathBuf {
    if n_estimates <= 1 {
        return file.to_path_buf();
    }
    let safe = crate::output::names::file_stem(name);
    let stem = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match file.extension() {
        Some(ext) => format!("{stem}.{safe}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{safe}"),
    };
    file.with_file_name(name)
}

/// Writes `traj` as TUM to `path` (temporary file + rename).
pub fn write_aligned(path: &Path, traj: &Trajectory) -> Result<()> {
    let mut bytes = Vec::new();
    // Writing into a Vec cannot fail.
    let _ = write_tum(&mut bytes, traj);
    write_output(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_path_names_each_estimates_file() {
        use std::path::{Path, PathBuf};
        assert_eq!(
            aligned_path(Path::new("out/al.tum"), "lio", 1),
            PathBuf::from("out/al.tum")
        );
        assert_eq!(
            aligned_path(Path::new("out/al.tum"), "estimate/odom", 2),
            PathBuf::from("out/al.estimate_odom.tum")
        );
        assert_eq!(
            aligned_path(Path::new("al"), "lio", 2),
            PathBuf::from("al.lio")
        );
    }
}

//! The fuzz targets' doors into the application's own readers: a batch manifest, a preset, a folder of
//! batch results merged into a summary. Behind the `fuzzing` feature, so that the modules behind them
//! stay private and rustc's dead-code lint sees them; not part of the API.

use std::path::Path;

use crate::batch::manifest::Manifest;
use crate::batch::merge::read_set;
use crate::batch::summary::Summary;
use crate::eval::parameters::Parameters;
use crate::eval::preset::Preset;

/// Reads `path` as a batch manifest (`manifest`) or as a preset; the outcome is dropped.
pub fn read_manifest_or_preset(path: &Path, manifest: bool) {
    if manifest {
        let _ = Manifest::from_toml(path, &Parameters::default());
    } else {
        let _ = Preset::load(&path.to_string_lossy());
    }
}

/// Merges the batch results in `dir` and renders every summary format; the outcome is dropped.
pub fn merge_folder(dir: &Path) {
    if let Ok(set) = read_set(std::slice::from_ref(&dir.to_path_buf())) {
        let mut s = Summary::build(&set.results);
        s.partial = !set.problems.is_empty();
        s.problems = set.problems;
        let _ = serde_json::to_vec(&s);
        let _ = s.to_csv();
        let _ = s.to_markdown();
        let _ = crate::batch::summary_html::render(&s, dir);
    }
}

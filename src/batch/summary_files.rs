//! A batch's summary on disk: `STEM.json`, `STEM.csv` and `STEM.md` (the forms of
//! [`super::summary`]) and `STEM.html` (the page of [`super::summary_html`]), each written to a
//! temporary file and renamed. `batch` and `merge` claim the same four paths before any work, so
//! the stem and the extensions are defined here once.

use std::path::{Path, PathBuf};

use super::summary::Summary;
use crate::error::Result;
use crate::output::{write_json, write_output};

/// The stem of a whole batch's summary (a shard writes [`super::shard::Shard::summary_stem`]).
pub const SUMMARY_STEM: &str = "summary";

/// The files of a summary, in the order they are written.
pub const EXTENSIONS: [&str; 4] = ["json", "csv", "md", "html"];

/// The paths of the summary `stem` in `dir`, one per [`EXTENSIONS`].
pub fn paths(dir: &Path, stem: &str) -> [PathBuf; 4] {
    EXTENSIONS.map(|ext| dir.join(format!("{stem}.{ext}")))
}

/// Writes `summary` as `STEM.json`, `STEM.csv`, `STEM.md` and `STEM.html` into `dir`.
pub fn write(summary: &Summary, dir: &Path, stem: &str) -> Result<()> {
    let [json, csv, md, html] = paths(dir, stem);
    write_json(&json, summary)?;
    write_output(&csv, summary.to_csv().as_bytes())?;
    write_output(&md, summary.to_markdown().as_bytes())?;
    write_output(&html, super::summary_html::render(summary, dir).as_bytes())
}

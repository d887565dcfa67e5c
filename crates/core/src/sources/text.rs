//! Text trajectory files of any supported format behind one door: TUM, KITTI, EuRoC ground truth and
//! generic CSV with a column mapping. The format is given (`--text-format`) or picked from the file:
//! EuRoC's header → EuRoC; other `.csv` files (or a header row of names) → CSV with `--csv` or, without
//! it, the columns `t,x,y,z[,qx,qy,qz,qw]`; otherwise the first data row decides: 12 numbers → KITTI,
//! 4 or 8 → TUM.
//!
//! [`TextSource`] makes a text file a [`Source`] with one channel, so `export` and the eval inputs treat
//! it like a recording.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::sources::euroc::{is_euroc_header, read_euroc_audited};
use crate::sources::kitti::read_kitti_audited;
use crate::sources::mapped_csv::{read_header, read_mapped_csv_audited, CsvMapping};
use crate::sources::tum::read_tum_audited;
use crate::sources::{ExtractOptions, ExtractedTopic, Extraction, Progress, Source, TopicInfo};
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// A text trajectory format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TextFormat {
    /// `t x y z [qx qy qz qw]`, seconds.
    Tum,
    /// 12 values a row (3×4 pose matrix), stamps from a times file or `i · 0.1 s`.
    Kitti,
    /// EuRoC MAV ground-truth CSV.
    Euroc,
    /// CSV with a column mapping.
    Csv,
}

impl TextFormat {
    /// Name as written in reports and flags.
    pub fn as_str(self) -> &'static str {
        match self {
            TextFormat::Tum => "tum",
            TextFormat::Kitti => "kitti",
            TextFormat::Euroc => "euroc",
            TextFormat::Csv => "csv",
        }
    }
}

/// How text files are read: shared by every `--reference-file`/`--estimate-file` of an evaluation.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TextOptions {
    /// Force a format (default: picked per file).
    pub format: Option<TextFormat>,
    /// `--csv`: the column mapping of CSV files (default: columns named t, x, y, z, qx, qy, qz, qw).
    pub csv: Option<CsvMapping>,
    /// `--kitti-times`: the KITTI `times.txt` (default: frame i at i · 0.1 s).
    pub kitti_times: Option<PathBuf>,
}

/// Picks the format of `path` from its extension, header and first data row.
pub fn detect_format(path: &Path) -> Result<TextFormat> {
    let is_csv_ext = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let head = read_header(path)?;
    if is_euroc_header(&head.columns) {
        return Ok(TextFormat::Euroc);
    }
    if is_csv_ext || (!head.is_data && !head.is_comment && head.columns.len() > 1) {
        return Ok(TextFormat::Csv);
    }
    let file = crate::sources::input::open_text(path)?;
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|e| Error::io(path, e))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let n = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .count();
        return match n {
            12 => Ok(TextFormat::Kitti),
            4 | 8 => Ok(TextFormat::Tum),
            _ => Err(Error::Text {
                path: path.to_path_buf(),
                line: i + 1,
                detail: format!("{n} values on the first row"),
                hint: "expected TUM (4 or 8 values), KITTI (12) or a CSV with a header; or give --text-format".into(),
            }),
        };
    }
    Ok(TextFormat::Tum)
}

/// Reads a text trajectory in the format `options` give or [`detect_format`] picks.
pub fn read_text(path: &Path, options: &TextOptions) -> Result<(Trajectory, TextFormat)> {
    read_text_audited(path, options).map(|(t, f, _)| (t, f))
}

/// [`read_text`], and what became of every row (dropped per reason, stamps going back).
pub fn read_text_audited(
    path: &Path,
    options: &TextOptions,
) -> Result<(Trajectory, TextFormat, RowAudit)> {
    let format = match options.format {
        Some(f) => f,
        None => detect_format(path)?,
    };
    let traj = match format {
        TextFormat::Tum => read_tum_audited(path)?,
        TextFormat::Kitti => read_kitti_audited(path, options.kitti_times.as_deref())?,
        TextFormat::Euroc => read_euroc_audited(path)?,
        TextFormat::Csv => {
            let mapping = match &options.csv {
                Some(m) => m.clone(),
                None => {
                    let head = read_header(path)?;
                    CsvMapping::by_name(&head.columns).ok_or_else(|| Error::Text {
                        path: path.to_path_buf(),
                        line: 1,
                        detail: format!(
                            "no columns named t, x, y, z (columns: {})",
                            head.columns.join(", ")
                        ),
                        hint: "give the mapping, e.g. --csv t=stamp:us,x=px,y=py,z=pz".into(),
                    })?
                }
            };
            read_mapped_csv_audited(path, &mapping)?
        }
    };
    Ok((traj.0, format, traj.1))
}

/// A text trajectory file as a [`Source`]: one channel, named by the file stem.
#[derive(Debug, Clone)]
pub struct TextSource {
    path: PathBuf,
    options: TextOptions,
}

impl TextSource {
    /// Opens `path` (nothing is read until asked).
    pub fn open(path: &Path, options: TextOptions) -> Result<Self> {
        std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        Ok(TextSource {
            path: path.to_path_buf(),
            options,
        })
    }

    /// The name of the file's single channel.
    pub fn channel(&self) -> String {
        self.path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    }
}

impl Source for TextSource {
    fn size_bytes(&self) -> u64 {
        std::fs::metadata(&self.path).map_or(0, |m| m.len())
    }

    fn topics(&self) -> Result<Vec<TopicInfo>> {
        let (traj, format) = read_text(&self.path, &self.options)?;
        Ok(vec![TopicInfo {
            topic: self.channel(),
            type_name: format.as_str().into(),
            message_encoding: "text".into(),
            message_count: traj.len() as u64,
            readable: true,
            frame_pairs: Vec::new(),
            tf_chains: Vec::new(),
        }])
    }

    /// Any requested name reads the file's one trajectory.
    fn extract(
        &self,
        topics: &[String],
        _options: &ExtractOptions,
        progress: Progress<'_>,
    ) -> Result<Extraction> {
        let (traj, format, rows) = read_text_audited(&self.path, &self.options)?;
        progress(self.size_bytes());
        Ok(Extraction {
            topics: topics
                .iter()
                .map(|t| ExtractedTopic {
                    topic: t.clone(),
                    type_name: format.as_str().into(),
                    messages: traj.len() as u64,
                    trajectory: traj.clone(),
                    invalid_dropped: rows.not_finite + rows.out_of_range,
                    duplicate_stamps: rows.duplicate_stamp,
                    rows,
                    geodetic_origin: None,
                })
                .collect(),
            warnings: Vec::new(),
            static_transforms: Vec::new(),
        })
    }
}

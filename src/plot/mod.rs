//! Figures of an evaluation (`--plot DIR`, `--html`): one file per figure kind, each taking plain data
//! so that it can be drawn from a report, from a sweep or from a test. [`mission_figures`] builds them
//! all from a report and the trajectories it was computed from.

pub mod de_distribution;
pub mod drift_error;
pub mod evo;
pub mod mission;
pub mod offset_curves;
pub mod offset_profile;
pub mod offset_search;
pub mod speed;
pub mod style;
pub mod sweep;
pub mod top_view;

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{Error, Result};
use crate::output::write_output;
use crate::trajectory::Trajectory;
pub use mission::mission_figures;
pub use style::PlotFormat;

/// What a figure shows.
#[derive(Debug, Clone)]
pub enum FigureData {
    TopView(top_view::TopView),
    DriftAlong(drift_error::DriftAlong),
    OffsetSearch(offset_search::OffsetSearch),
    OffsetProfile(offset_profile::OffsetProfile),
    Speed(speed::SpeedFit),
    Sweep(sweep::SweepFigure),
    DeDistribution(de_distribution::DeDistribution),
}

impl style::Draw for FigureData {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        match self {
            FigureData::TopView(f) => f.draw(root),
            FigureData::DriftAlong(f) => f.draw(root),
            FigureData::OffsetSearch(f) => f.draw(root),
            FigureData::OffsetProfile(f) => f.draw(root),
            FigureData::Speed(f) => f.draw(root),
            FigureData::Sweep(f) => f.draw(root),
            FigureData::DeDistribution(f) => f.draw(root),
        }
    }
}

/// A figure with its file name (without extension) and title.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File stem, e.g. `odom_top_view`.
    pub name: String,
    pub title: String,
    pub data: FigureData,
}

impl Figure {
    /// The figure as SVG text.
    pub fn svg(&self) -> Result<String> {
        style::render_svg(&self.data)
    }

    /// Writes `DIR/<name>.<ext>` (temporary file + rename) and returns its path.
    pub fn write(&self, dir: &Path, format: PlotFormat) -> Result<PathBuf> {
        let path = dir.join(format!("{}.{}", self.name, format.extension()));
        match format {
            PlotFormat::Svg => write_output(&path, self.svg()?.as_bytes())?,
            PlotFormat::Png => style::render_png(&self.data, &path)?,
        }
        Ok(path)
    }
}

/// Writes every figure into `dir` (created if missing).
pub fn write_figures(figures: &[Figure], dir: &Path, format: PlotFormat) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Output {
        path: dir.to_path_buf(),
        detail: e.to_string(),
    })?;
    figures.iter().map(|f| f.write(dir, format)).collect()
}

/// A file-name-safe form of an estimate's name.
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect::<String>()
        .trim_matches('_')
        .to_string()
}

/// The trajectories a mission's figures are drawn from: the reference as the evaluation cropped it,
/// and each estimate, by name, on its own clock (the figures move it as the report's clock correction
/// did).
#[derive(Debug, Clone, Copy)]
pub struct Trajectories<'a> {
    pub reference: &'a Trajectory,
    pub estimates: &'a [(&'a str, &'a Trajectory)],
}

/// Where a mission's pictures go: `--plot DIR` (in `format`) and/or `--html FILE`.
#[derive(Debug, Clone, Default)]
pub struct PictureOutputs {
    pub plot_dir: Option<PathBuf>,
    pub format: Option<PlotFormat>,
    pub html: Option<PathBuf>,
}

impl PictureOutputs {
    /// Whether anything is asked for.
    pub fn any(&self) -> bool {
        self.plot_dir.is_some() || self.html.is_some()
    }

    /// Draws the figures of `report` and writes what is asked for; returns the files written.
    pub fn write(
        &self,
        report: &crate::report::json::Report,
        inputs: Trajectories<'_>,
    ) -> Result<Vec<PathBuf>> {
        if !self.any() {
            return Ok(Vec::new());
        }
        let figures = mission_figures(report, &inputs);
        let mut written = Vec::new();
        if let Some(dir) = &self.plot_dir {
            written.extend(write_figures(
                &figures,
                dir,
                self.format.unwrap_or(PlotFormat::Svg),
            )?);
        }
        if let Some(path) = &self.html {
            let svgs = figures
                .iter()
                .map(|f| f.svg())
                .collect::<Result<Vec<_>>>()?;
            let inline: Vec<crate::render::html::InlineFigure<'_>> = figures
                .iter()
                .zip(&svgs)
                .map(|(f, s)| crate::render::html::InlineFigure {
                    title: &f.title,
                    svg: s,
                })
                .collect();
            let html = crate::render::html::render_report(report, &inline);
            write_output(path, html.as_bytes())?;
            written.push(path.clone());
        }
        Ok(written)
    }
}

//! Figures of an evaluation (`--plot DIR`, `--html`): one file per figure kind, each taking plain data
//! so that it can be drawn from a report, from a sweep or from a test. [`mission_figures`] builds them
//! all from a report and the trajectories it was computed from.

pub mod clock_domains;
pub mod de_distribution;
pub mod drift_error;
pub mod evo;
pub mod mission;
pub mod offset_curves;
pub mod offset_matrix;
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
use crate::output::names::file_stems;
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

    /// Writes `DIR/<name>.<ext>` with the one file writer and returns its path.
    pub fn write(&self, dir: &Path, format: PlotFormat) -> Result<PathBuf> {
        let path = dir.join(format!("{}.{}", self.name, format.extension()));
        match format {
            PlotFormat::Svg => write_output(&path, self.svg()?.as_bytes())?,
            PlotFormat::Png => write_output(&path, &style::render_png(&self.data)?)?,
        }
        Ok(path)
    }
}

/// Writes every figure into `dir` (created if missing).
pub fn write_figures(figures: &[Figure], dir: &Path, format: PlotFormat) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::output(dir, &e))?;
    figures.iter().map(|f| f.write(dir, format)).collect()
}

/// The kinds of figure each estimate may get, the end of its file names (`<estimate>_<kind>`).
pub const FIGURE_KINDS: [&str; 5] = [
    "top_view",
    "drift_error",
    "offset_search",
    "offset_profile",
    "speed",
];

/// Every file `--plot DIR` may write for estimates named `names`, known before the evaluation so that
/// each is claimed as an output first; refused when two names map to one file name.
pub fn figure_files(dir: &Path, names: &[&str], format: PlotFormat) -> Result<Vec<PathBuf>> {
    let stems = file_stems(
        "estimates",
        names.iter().copied(),
        "name them with --estimate NAME=TOPIC",
    )?;
    Ok(stems
        .iter()
        .flat_map(|stem| {
            FIGURE_KINDS
                .iter()
                .map(move |k| dir.join(format!("{stem}_{k}.{}", format.extension())))
        })
        .collect())
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

    /// Claims every file these pictures may write for estimates named `estimates` (the HTML page, the
    /// `--plot` folder and each figure in it) before the evaluation: refused when one is an input,
    /// lies in an input folder, or is another output's path.
    pub fn claim(&self, guard: &mut crate::output::OutputGuard, estimates: &[&str]) -> Result<()> {
        if let Some(h) = &self.html {
            guard.claim("--html", h)?;
        }
        if let Some(dir) = &self.plot_dir {
            guard.claim_dir("--plot", dir)?;
            let format = self.format.unwrap_or(PlotFormat::Svg);
            for f in figure_files(dir, estimates, format)? {
                guard.claim("--plot", &f)?;
            }
        }
        Ok(())
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

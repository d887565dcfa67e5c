//! The figures of evo's command line, drawn as files without a display: `ape`/`rpe -p` (the error
//! against index, seconds or distance with its statistics; the trajectories with the error as colour;
//! the statistics as bars), `res -p` (every result's raw values, statistics bars, histograms, box and
//! violin plots) and `traj -p` (the trajectories, x/y/z over time). Each figure takes plain data.
//!
//! evo's `--plot_mode` picks the axes of the trajectory figures: `xy`, `xz`, `yx`, `yz`, `zx`, `zy`
//! draw that plane at equal scale, `xyz` a 3-D view.

use plotters::coord::cartesian::Cartesian3d;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{
    category_at, category_chart, decimate, label_font, legend, padded_range, plot_err,
    series_color, title_font, viridis, xy_chart, Draw, FAMILY, MAX_POINTS,
};
use crate::error::{Error, Result};
use crate::stats::quantile_sorted;

/// evo's `--plot_mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlotMode {
    Xy,
    Xz,
    Yx,
    Yz,
    Zx,
    Zy,
    #[default]
    Xyz,
}

impl PlotMode {
    /// Parses evo's word.
    pub fn parse(s: &str) -> Result<PlotMode> {
        Ok(match s {
            "xy" => PlotMode::Xy,
            "xz" => PlotMode::Xz,
            "yx" => PlotMode::Yx,
            "yz" => PlotMode::Yz,
            "zx" => PlotMode::Zx,
            "zy" => PlotMode::Zy,
            "xyz" => PlotMode::Xyz,
            _ => {
                return Err(Error::InvalidArgument(format!(
                    "--plot_mode {s}: expected xy, xz, yx, yz, zx, zy or xyz"
                )))
            }
        })
    }

    /// The two axes of a plane mode (indices into x, y, z), `None` for `xyz`.
    pub fn axes(self) -> Option<(usize, usize)> {
        Some(match self {
            PlotMode::Xy => (0, 1),
            PlotMode::Xz => (0, 2),
            PlotMode::Yx => (1, 0),
            PlotMode::Yz => (1, 2),
            PlotMode::Zx => (2, 0),
            PlotMode::Zy => (2, 1),
            PlotMode::Xyz => return None,
        })
    }
}

const AXIS: [&str; 3] = ["x (m)", "y (m)", "z (m)"];

/// Values against index, seconds or distance, one series per result, with horizontal lines of
/// statistics (evo's "raw" figure).
#[derive(Debug, Clone, Default)]
pub struct ErrorSeries {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<(String, Vec<(f64, f64)>)>,
    /// (name, value) drawn as dashed lines: rmse, median, mean; `std` as a band around the mean.
    pub stats: Vec<(String, f64)>,
    /// Circle markers on the values (`res --plot_markers`).
    pub markers: bool,
}

impl Draw for ErrorSeries {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let all = || self.series.iter().flat_map(|s| s.1.iter());
        let (x0, x1) = padded_range(all().map(|p| p.0));
        let (y0, y1) = padded_range(all().map(|p| p.1).chain([0.0]));
        let mut chart = xy_chart(
            root,
            &self.title,
            ((x0, x1), (y0.min(0.0), y1)),
            (&self.x_label, &self.y_label),
        )?;
        let n = self.series.len();
        let mean = self.stats.iter().find(|s| s.0 == "mean").map(|s| s.1);
        if let (Some(m), Some(sd)) = (mean, self.stats.iter().find(|s| s.0 == "std")) {
            let c = RGBColor(150, 150, 150);
            chart
                .draw_series([Rectangle::new(
                    [(x0, m - sd.1), (x1, m + sd.1)],
                    c.mix(0.2).filled(),
                )])
                .map_err(plot_err)?
                .label(format!("std {:.6}", sd.1))
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 20, y + 5)], c.mix(0.3).filled())
                });
        }
        for (i, (name, pts)) in self.series.iter().enumerate() {
            let c = series_color(i, n.max(2));
            let p: Vec<(f64, f64)> = decimate(pts.len(), MAX_POINTS)
                .into_iter()
                .map(|k| pts[k])
                .collect();
            let s = LineSeries::new(p, c.stroke_width(1));
            let s = if self.markers { s.point_size(2) } else { s };
            chart
                .draw_series(s)
                .map_err(plot_err)?
                .label(name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        let palette = [
            RGBColor(213, 94, 0),
            RGBColor(0, 158, 115),
            RGBColor(204, 121, 167),
            RGBColor(86, 180, 233),
        ];
        for (k, (name, v)) in self.stats.iter().filter(|s| s.0 != "std").enumerate() {
            let c = palette[k % palette.len()];
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, *v), (x1, *v)],
                    8,
                    5,
                    c.stroke_width(2),
                ))
                .map_err(plot_err)?
                .label(format!("{name} {v:.6}"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

/// Trajectories in a plane (equal scale) or in 3-D: the reference dashed grey, the estimate
/// coloured by its per-pose value on `[cmin, cmax]` (evo's "map" figure), or several trajectories
/// in their own colours (evo_traj).
#[derive(Debug, Clone, Default)]
pub struct TrajectoryMap {
    pub title: String,
    pub mode: PlotMode,
    /// The reference (grey, dashed), if any.
    pub reference: Option<Vec<[f64; 3]>>,
    /// Trajectories in series colours.
    pub trajectories: Vec<(String, Vec<[f64; 3]>)>,
    /// The estimate coloured by value, with the value's name and colour range.
    pub coloured: Option<Coloured>,
}

/// An estimate coloured by its values.
#[derive(Debug, Clone, Default)]
pub struct Coloured {
    pub name: String,
    pub positions: Vec<[f64; 3]>,
    pub values: Vec<f64>,
    pub cmin: f64,
    pub cmax: f64,
    pub value_label: String,
}

const BAR_W: u32 = 130;

/// A 3-D chart over metres on every axis.
type Chart3d<'a, DB> =
    ChartContext<'a, DB, Cartesian3d<RangedCoordf64, RangedCoordf64, RangedCoordf64>>;

impl TrajectoryMap {
    fn every_position(&self) -> impl Iterator<Item = &[f64; 3]> {
        self.reference
            .iter()
            .flatten()
            .chain(self.trajectories.iter().flat_map(|t| t.1.iter()))
            .chain(self.coloured.iter().flat_map(|c| c.positions.iter()))
    }

    fn colour(&self, v: f64) -> RGBColor {
        let c = self.coloured.as_ref().expect("coloured");
        let span = (c.cmax - c.cmin).max(1e-12);
        viridis((v - c.cmin) / span)
    }
}

fn thin<T: Copy>(v: &[T]) -> Vec<T> {
    decimate(v.len(), MAX_POINTS)
        .into_iter()
        .map(|k| v[k])
        .collect()
}

impl Draw for TrajectoryMap {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (w, _) = root.dim_in_pixel();
        let (area, bar) = if self.coloured.is_some() {
            let (a, b) = root.split_horizontally(w - BAR_W);
            (a, Some(b))
        } else {
            (root.clone(), None)
        };
        match self.mode.axes() {
            Some(axes) => self.draw_plane(&area, axes)?,
            None => self.draw_3d(&area)?,
        }
        if let (Some(bar), Some(c)) = (bar, &self.coloured) {
            colour_bar(&bar, c.cmin, c.cmax, &c.value_label)?;
        }
        Ok(())
    }
}

impl TrajectoryMap {
    fn draw_plane<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (a, b): (usize, usize),
    ) -> Result<()> {
        let (lw, lh) = area.dim_in_pixel();
        let px = (
            (lw as f64 - 80.0 - 20.0).max(10.0),
            (lh as f64 - 40.0 - 50.0 - 20.0).max(10.0),
        );
        let (x0, x1) = padded_range(self.every_position().map(|p| p[a]));
        let (y0, y1) = padded_range(self.every_position().map(|p| p[b]));
        let m_per_px = ((x1 - x0) / px.0).max((y1 - y0) / px.1);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let (hx, hy) = (0.5 * m_per_px * px.0, 0.5 * m_per_px * px.1);
        let mut chart = xy_chart(
            area,
            &self.title,
            ((cx - hx, cx + hx), (cy - hy, cy + hy)),
            (AXIS[a], AXIS[b]),
        )?;
        let flat = |p: &[f64; 3]| (p[a], p[b]);
        if let Some(r) = &self.reference {
            let grey = RGBColor(110, 110, 110);
            chart
                .draw_series(DashedLineSeries::new(
                    thin(r).iter().map(flat),
                    6,
                    4,
                    grey.stroke_width(2),
                ))
                .map_err(plot_err)?
                .label("reference")
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(2))
                });
        }
        self.draw_estimates(&mut chart, flat)?;
        legend(&mut chart, SeriesLabelPosition::UpperLeft)
    }

    /// The trajectories, each a line of its own colour, and the coloured estimate's segments, on a
    /// 2-D or 3-D chart: `at` places a position in the chart's coordinates.
    fn draw_estimates<DB, CT, P>(
        &self,
        chart: &mut ChartContext<'_, DB, CT>,
        at: impl Fn(&[f64; 3]) -> P + Copy,
    ) -> Result<()>
    where
        DB: DrawingBackend,
        CT: CoordTranslate<From = P>,
        P: Clone + 'static,
    {
        let n = self.trajectories.len();
        for (i, (name, t)) in self.trajectories.iter().enumerate() {
            let c = series_color(i, n);
            chart
                .draw_series(LineSeries::new(thin(t).iter().map(at), c.stroke_width(2)))
                .map_err(plot_err)?
                .label(name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        if let Some(c) = &self.coloured {
            let ids = decimate(c.positions.len(), MAX_POINTS);
            let segs: Vec<PathElement<P>> = ids
                .windows(2)
                .map(|w| {
                    let col = self.colour(c.values[w[1]]);
                    PathElement::new(
                        vec![at(&c.positions[w[0]]), at(&c.positions[w[1]])],
                        col.stroke_width(3),
                    )
                })
                .collect();
            chart
                .draw_series(segs)
                .map_err(plot_err)?
                .label(c.name.clone())
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], viridis(0.5).stroke_width(3))
                });
        }
        Ok(())
    }

    /// The 3-D view: the reference, the trajectories and the coloured estimate in the cube of
    /// [`TrajectoryMap::chart_3d`], z up.
    fn draw_3d<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()> {
        let mut chart = self.chart_3d(area)?;
        let up = |p: &[f64; 3]| (p[0], p[2], p[1]);
        if let Some(r) = &self.reference {
            let grey = RGBColor(110, 110, 110);
            chart
                .draw_series(LineSeries::new(
                    thin(r).iter().map(up),
                    grey.stroke_width(1),
                ))
                .map_err(plot_err)?
                .label("reference")
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(2))
                });
        }
        self.draw_estimates(&mut chart, up)?;
        legend(&mut chart, SeriesLabelPosition::UpperLeft)
    }

    /// The titled 3-D chart with its axes drawn: one scale on all axes (a cube around every position,
    /// as evo's `plot_xyz_realistic`), seen from a fixed yaw and pitch.
    fn chart_3d<'a, DB: DrawingBackend>(
        &self,
        area: &'a DrawingArea<DB, Shift>,
    ) -> Result<Chart3d<'a, DB>> {
        let r = |k: usize| padded_range(self.every_position().map(|p| p[k]));
        let ((x0, x1), (y0, y1), (z0, z1)) = (r(0), r(1), r(2));
        // One scale on all axes, as evo's plot_xyz_realistic.
        let half = [(x1 - x0), (y1 - y0), (z1 - z0)]
            .into_iter()
            .fold(0.0f64, f64::max)
            / 2.0;
        let c = |a: f64, b: f64| ((a + b) / 2.0 - half, (a + b) / 2.0 + half);
        let ((x0, x1), (y0, y1), (z0, z1)) = (c(x0, x1), c(y0, y1), c(z0, z1));
        // plotters' 3-D axes are (x, y up, z depth): our z goes up.
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, title_font())
            .margin(20)
            .build_cartesian_3d(x0..x1, z0..z1, y0..y1)
            .map_err(plot_err)?;
        chart.with_projection(|mut p| {
            p.yaw = 0.6;
            p.pitch = 0.35;
            p.scale = 0.8;
            p.into_matrix()
        });
        chart
            .configure_axes()
            .label_style(label_font())
            .draw()
            .map_err(plot_err)?;
        Ok(chart)
    }
}

/// A vertical viridis bar from `lo` to `hi` with five labels.
fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    lo: f64,
    hi: f64,
    label: &str,
) -> Result<()> {
    let (_, h) = area.dim_in_pixel();
    let (y0, y1) = (60i32, h as i32 - 60);
    let x = 10i32;
    let steps = 100i32;
    let edge = |k: i32| y1 - ((y1 - y0) as f64 * k as f64 / steps as f64).round() as i32;
    for k in 0..steps {
        area.draw(&Rectangle::new(
            [(x, edge(k + 1)), (x + 24, edge(k))],
            viridis(k as f64 / steps as f64).filled(),
        ))
        .map_err(plot_err)?;
    }
    for k in 0..=4 {
        let f = k as f64 / 4.0;
        let y = y1 - ((y1 - y0) as f64 * f) as i32;
        area.draw(&Text::new(
            format!("{:.4}", lo + f * (hi - lo)),
            (x + 30, y - 7),
            label_font(),
        ))
        .map_err(plot_err)?;
    }
    area.draw(&Text::new(
        label.to_string(),
        (x, y0 - 30),
        (FAMILY, 15).into_font(),
    ))
    .map_err(plot_err)
}

/// Statistics as horizontal bars: one group per statistic, one bar per result (evo's "stats").
#[derive(Debug, Clone, Default)]
pub struct StatsBars {
    pub title: String,
    pub value_label: String,
    /// The statistics' names, top to bottom.
    pub stats: Vec<String>,
    /// Per result: its label and one value per statistic.
    pub results: Vec<(String, Vec<f64>)>,
}

impl Draw for StatsBars {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let g = self.stats.len().max(1);
        let n = self.results.len().max(1);
        let (_, hi) = padded_range(
            self.results
                .iter()
                .flat_map(|r| r.1.iter().copied())
                .chain([0.0]),
        );
        let names = self.stats.clone();
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font())
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..hi, -0.5..(g as f64 - 0.5))
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .y_labels(g)
            .y_label_formatter(&|y| {
                category_at(*y)
                    .and_then(|i| g.checked_sub(1 + i))
                    .and_then(|i| names.get(i).cloned())
                    .unwrap_or_default()
            })
            .x_desc(self.value_label.as_str())
            .label_style(label_font())
            .axis_desc_style(label_font())
            .disable_y_mesh()
            .draw()
            .map_err(plot_err)?;
        let h = 0.8 / n as f64;
        for (k, (label, values)) in self.results.iter().enumerate() {
            let c = series_color(k, n.max(2));
            let bars: Vec<Rectangle<(f64, f64)>> = values
                .iter()
                .enumerate()
                .map(|(s, &v)| {
                    let y = (g - 1 - s) as f64 + 0.4 - h * (k as f64 + 1.0);
                    Rectangle::new([(0.0, y), (v, y + h)], c.filled())
                })
                .collect();
            chart
                .draw_series(bars)
                .map_err(plot_err)?
                .label(label.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], c.filled()));
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight)
    }
}

/// Each result's histogram of values, in a grid of panels (evo's "histogram").
#[derive(Debug, Clone, Default)]
pub struct Histograms {
    pub title: String,
    pub value_label: String,
    pub results: Vec<(String, Vec<f64>)>,
}

impl Draw for Histograms {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (top, body) = root.split_vertically(36);
        top.draw(&Text::new(self.title.clone(), (10, 8), title_font()))
            .map_err(plot_err)?;
        let n = self.results.len().max(1);
        let cols = if n <= 2 { n } else { n.div_ceil(2) };
        let rows = n.div_ceil(cols);
        let panels = body.split_evenly((rows, cols));
        let (lo, hi) = padded_range(self.results.iter().flat_map(|r| r.1.iter().copied()));
        for (k, ((label, values), panel)) in self.results.iter().zip(panels.iter()).enumerate() {
            let bins = ((values.len() as f64).sqrt().ceil() as usize).clamp(5, 60);
            let width = (hi - lo) / bins as f64;
            let mut counts = vec![0usize; bins];
            for v in values.iter().filter(|v| v.is_finite()) {
                let b = (((v - lo) / width) as usize).min(bins - 1);
                counts[b] += 1;
            }
            let total = values.len().max(1) as f64;
            let dens: Vec<f64> = counts.iter().map(|&c| c as f64 / total / width).collect();
            let top_d = dens.iter().copied().fold(0.0, f64::max) * 1.1 + 1e-12;
            let mut chart = xy_chart(
                panel,
                label,
                ((lo, hi), (0.0, top_d)),
                (self.value_label.as_str(), "density"),
            )?;
            let c = series_color(k, n.max(2));
            chart
                .draw_series(dens.iter().enumerate().map(|(b, &d)| {
                    let x = lo + b as f64 * width;
                    Rectangle::new([(x, 0.0), (x + width, d)], c.mix(0.6).filled())
                }))
                .map_err(plot_err)?;
        }
        Ok(())
    }
}

/// Box plots (quartiles, whiskers at 1.5 IQR, outliers as dots) or violins (a kernel density
/// estimate mirrored, quartiles inside) of each result's values (evo's "box_plot" and
/// "violin_histogram").
#[derive(Debug, Clone, Default)]
pub struct Distributions {
    pub title: String,
    pub value_label: String,
    pub results: Vec<(String, Vec<f64>)>,
    pub violin: bool,
}

impl Draw for Distributions {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let n = self.results.len().max(1);
        let (lo, hi) = padded_range(self.results.iter().flat_map(|r| r.1.iter().copied()));
        let labels: Vec<String> = self.results.iter().map(|r| r.0.clone()).collect();
        let mut chart = category_chart(
            root,
            &self.title,
            &labels,
            (lo, hi),
            ("estimate", self.value_label.as_str()),
            80,
        )?;
        for (k, (_, values)) in self.results.iter().enumerate() {
            let mut s: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
            if s.is_empty() {
                continue;
            }
            s.sort_by(f64::total_cmp);
            let c = series_color(k, n.max(2));
            if self.violin {
                self.violin(&mut chart, &s, k as f64, c)?;
            } else {
                self.box_plot(&mut chart, &s, k as f64, c)?;
            }
        }
        Ok(())
    }
}

/// The first quartile, the median and the third quartile of sorted values.
fn quartiles(s: &[f64]) -> (f64, f64, f64) {
    (
        quantile_sorted(s, 0.25),
        quantile_sorted(s, 0.5),
        quantile_sorted(s, 0.75),
    )
}

impl Distributions {
    /// One violin at `x` ([`Distributions::violin_shape`]) with its quartiles as a black bar and
    /// its median as a white dot; `s` sorted and finite.
    fn violin<DB: DrawingBackend>(
        &self,
        chart: &mut super::style::Chart<'_, DB>,
        s: &[f64],
        x: f64,
        c: RGBColor,
    ) -> Result<()> {
        let (q1, med, q3) = quartiles(s);
        self.violin_shape(chart, s, x, c)?;
        chart
            .draw_series([Rectangle::new(
                [(x - 0.03, q1), (x + 0.03, q3)],
                BLACK.filled(),
            )])
            .map_err(plot_err)?;
        chart
            .draw_series([Circle::new((x, med), 4, WHITE.filled())])
            .map_err(plot_err)?;
        Ok(())
    }

    /// One box at `x`: the quartiles as a box, the median as a line, whiskers to the furthest values
    /// within 1.5 IQR of the box, the values beyond them as circles; `s` sorted and finite.
    fn box_plot<DB: DrawingBackend>(
        &self,
        chart: &mut super::style::Chart<'_, DB>,
        s: &[f64],
        x: f64,
        c: RGBColor,
    ) -> Result<()> {
        let (q1, med, q3) = quartiles(s);
        let iqr = q3 - q1;
        let lo_w = s
            .iter()
            .copied()
            .find(|&v| v >= q1 - 1.5 * iqr)
            .unwrap_or(q1);
        let hi_w = s
            .iter()
            .rev()
            .copied()
            .find(|&v| v <= q3 + 1.5 * iqr)
            .unwrap_or(q3);
        chart
            .draw_series([Rectangle::new(
                [(x - 0.3, q1), (x + 0.3, q3)],
                c.mix(0.5).filled(),
            )])
            .map_err(plot_err)?;
        let lines = vec![
            vec![(x - 0.3, med), (x + 0.3, med)],
            vec![(x, q3), (x, hi_w)],
            vec![(x, q1), (x, lo_w)],
            vec![(x - 0.15, hi_w), (x + 0.15, hi_w)],
            vec![(x - 0.15, lo_w), (x + 0.15, lo_w)],
        ];
        chart
            .draw_series(
                lines
                    .into_iter()
                    .map(|l| PathElement::new(l, BLACK.stroke_width(2))),
            )
            .map_err(plot_err)?;
        let outliers: Vec<f64> = s
            .iter()
            .copied()
            .filter(|&v| v < lo_w || v > hi_w)
            .collect();
        chart
            .draw_series(
                thin(&outliers)
                    .into_iter()
                    .map(|v| Circle::new((x, v), 3, BLACK.stroke_width(1))),
            )
            .map_err(plot_err)?;
        Ok(())
    }

    /// A mirrored Gaussian kernel density estimate (Scott's bandwidth, as seaborn's default) at
    /// `x`, scaled to a half-width of 0.4.
    fn violin_shape<DB: DrawingBackend>(
        &self,
        chart: &mut super::style::Chart<'_, DB>,
        s: &[f64],
        x: f64,
        c: RGBColor,
    ) -> Result<()> {
        let n = s.len() as f64;
        let mean = s.iter().sum::<f64>() / n;
        let sd = (s.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
        let bw = (sd * n.powf(-0.2)).max(1e-12);
        let (a, b) = (s[0], s[s.len() - 1]);
        let sample: Vec<f64> = thin(s);
        let grid: Vec<f64> = (0..=100).map(|k| a + (b - a) * k as f64 / 100.0).collect();
        let dens: Vec<f64> = grid
            .iter()
            .map(|&g| {
                sample
                    .iter()
                    .map(|v| (-0.5 * ((g - v) / bw).powi(2)).exp())
                    .sum::<f64>()
            })
            .collect();
        let top = dens.iter().copied().fold(0.0, f64::max).max(1e-300);
        let mut outline: Vec<(f64, f64)> = grid
            .iter()
            .zip(&dens)
            .map(|(&g, &d)| (x + 0.4 * d / top, g))
            .collect();
        outline.extend(
            grid.iter()
                .zip(&dens)
                .rev()
                .map(|(&g, &d)| (x - 0.4 * d / top, g)),
        );
        chart
            .draw_series([Polygon::new(outline, c.mix(0.6).filled())])
            .map_err(plot_err)?;
        Ok(())
    }
}

/// A named trajectory as (time, position) samples.
pub type TimedTrajectory = (String, Vec<(f64, [f64; 3])>);

/// x, y and z over time, one panel each, one line per trajectory (evo_traj's "xyz" figure).
#[derive(Debug, Clone, Default)]
pub struct XyzOverTime {
    pub title: String,
    pub x_label: String,
    /// Per trajectory: its name and (time, position).
    pub trajectories: Vec<TimedTrajectory>,
}

impl Draw for XyzOverTime {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (top, body) = root.split_vertically(36);
        top.draw(&Text::new(self.title.clone(), (10, 8), title_font()))
            .map_err(plot_err)?;
        let panels = body.split_evenly((3, 1));
        let n = self.trajectories.len();
        let (t0, t1) = padded_range(
            self.trajectories
                .iter()
                .flat_map(|t| t.1.iter().map(|p| p.0)),
        );
        for (k, panel) in panels.iter().enumerate() {
            let (lo, hi) = padded_range(
                self.trajectories
                    .iter()
                    .flat_map(|t| t.1.iter().map(|p| p.1[k])),
            );
            let mut chart = ChartBuilder::on(panel)
                .margin(5)
                .x_label_area_size(if k == 2 { 40 } else { 20 })
                .y_label_area_size(80)
                .build_cartesian_2d(t0..t1, lo..hi)
                .map_err(plot_err)?;
            chart
                .configure_mesh()
                .x_desc(if k == 2 { self.x_label.as_str() } else { "" })
                .y_desc(AXIS[k])
                .label_style(label_font())
                .axis_desc_style(label_font())
                .draw()
                .map_err(plot_err)?;
            for (i, (name, pts)) in self.trajectories.iter().enumerate() {
                let c = series_color(i, n);
                let s = chart
                    .draw_series(LineSeries::new(
                        thin(pts).into_iter().map(|(t, p)| (t, p[k])),
                        c.stroke_width(1),
                    ))
                    .map_err(plot_err)?;
                if k == 0 {
                    s.label(name.clone()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    });
                }
            }
            if k == 0 {
                legend(&mut chart, SeriesLabelPosition::UpperRight)?;
            }
        }
        Ok(())
    }
}

/// Any of evo's figures.
#[derive(Debug, Clone)]
pub enum EvoFigure {
    Errors(ErrorSeries),
    Map(TrajectoryMap),
    Stats(StatsBars),
    Histograms(Histograms),
    Distributions(Distributions),
    Xyz(XyzOverTime),
}

impl Draw for EvoFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        match self {
            EvoFigure::Errors(f) => f.draw(root),
            EvoFigure::Map(f) => f.draw(root),
            EvoFigure::Stats(f) => f.draw(root),
            EvoFigure::Histograms(f) => f.draw(root),
            EvoFigure::Distributions(f) => f.draw(root),
            EvoFigure::Xyz(f) => f.draw(root),
        }
    }
}

/// How `--save_plot FILE` is written: evo writes one file per figure, `BASE_NAME.EXT`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlotTarget {
    /// `FILE` without its extension.
    pub base: std::path::PathBuf,
    pub format: super::PlotFormat,
}

impl PlotTarget {
    /// The target of `--save_plot FILE`: SVG or PNG by the extension (none: SVG). PDF has no backend
    /// in plotters: `Err` with the SVG target to use instead, for the caller to say so.
    pub fn of(file: &std::path::Path) -> std::result::Result<PlotTarget, PlotTarget> {
        let ext = file
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        let base = match ext {
            Some(_) => file.with_extension(""),
            None => file.to_path_buf(),
        };
        match ext.as_deref() {
            Some("png") => Ok(PlotTarget {
                base,
                format: super::PlotFormat::Png,
            }),
            Some("svg") | None => Ok(PlotTarget {
                base,
                format: super::PlotFormat::Svg,
            }),
            Some(_) => Err(PlotTarget {
                base,
                format: super::PlotFormat::Svg,
            }),
        }
    }

    /// The file of figure `name`.
    pub fn path(&self, name: &str) -> std::path::PathBuf {
        let stem = self
            .base
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        self.base
            .with_file_name(format!("{stem}_{name}.{}", self.format.extension()))
    }

    /// Writes each `(name, figure)` to its file; returns the files.
    pub fn write(&self, figures: &[(String, EvoFigure)]) -> Result<Vec<std::path::PathBuf>> {
        let mut out = Vec::new();
        for (name, f) in figures {
            let path = self.path(name);
            match self.format {
                super::PlotFormat::Svg => {
                    crate::output::write_output(&path, super::style::render_svg(f)?.as_bytes())?
                }
                super::PlotFormat::Png => {
                    crate::output::write_output(&path, &super::style::render_png(f)?)?
                }
            }
            out.push(path);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn save_plot_names_are_evos() {
        let t = PlotTarget::of(std::path::Path::new("out/ape.svg")).unwrap();
        assert_eq!(t.path("raw"), std::path::PathBuf::from("out/ape_raw.svg"));
        let t = PlotTarget::of(std::path::Path::new("a.PNG")).unwrap();
        assert_eq!(t.path("map"), std::path::PathBuf::from("a_map.png"));
        let pdf = PlotTarget::of(std::path::Path::new("a.pdf")).unwrap_err();
        assert_eq!(pdf.path("map"), std::path::PathBuf::from("a_map.svg"));
    }

    #[test]
    fn every_figure_draws_in_both_formats() {
        let pts: Vec<[f64; 3]> = (0..200)
            .map(|i| {
                let a = i as f64 * 0.05;
                [a.cos() * 5.0, a.sin() * 3.0, 0.01 * i as f64]
            })
            .collect();
        let vals: Vec<f64> = (0..200).map(|i| (i as f64 * 0.1).sin().abs()).collect();
        let results = vec![
            ("a".to_string(), vals.clone()),
            ("b".to_string(), vals[50..].to_vec()),
        ];
        let mut figs = vec![
            EvoFigure::Errors(ErrorSeries {
                title: "APE".into(),
                x_label: "t (s)".into(),
                y_label: "APE (m)".into(),
                series: vec![(
                    "est".into(),
                    vals.iter()
                        .enumerate()
                        .map(|(i, &v)| (i as f64, v))
                        .collect(),
                )],
                stats: vec![
                    ("rmse".into(), 0.7),
                    ("mean".into(), 0.6),
                    ("std".into(), 0.2),
                ],
                markers: true,
            }),
            EvoFigure::Stats(StatsBars {
                title: "s".into(),
                value_label: "APE (m)".into(),
                stats: vec!["rmse".into(), "mean".into()],
                results: vec![("a".into(), vec![0.7, 0.6]), ("b".into(), vec![0.8, 0.5])],
            }),
            EvoFigure::Histograms(Histograms {
                title: "h".into(),
                value_label: "APE (m)".into(),
                results: results.clone(),
            }),
            EvoFigure::Distributions(Distributions {
                title: "v".into(),
                value_label: "APE (m)".into(),
                results: results.clone(),
                violin: true,
            }),
            EvoFigure::Distributions(Distributions {
                title: "b".into(),
                value_label: "APE (m)".into(),
                results,
                violin: false,
            }),
            EvoFigure::Xyz(XyzOverTime {
                title: "xyz".into(),
                x_label: "t (s)".into(),
                trajectories: vec![(
                    "a".into(),
                    pts.iter()
                        .enumerate()
                        .map(|(i, p)| (i as f64, *p))
                        .collect(),
                )],
            }),
        ];
        for mode in [PlotMode::Xy, PlotMode::Zy, PlotMode::Xyz] {
            figs.push(EvoFigure::Map(TrajectoryMap {
                title: "map".into(),
                mode,
                reference: Some(pts.clone()),
                trajectories: vec![("other".into(), pts[10..].to_vec())],
                coloured: Some(Coloured {
                    name: "est".into(),
                    positions: pts.clone(),
                    values: vals.clone(),
                    cmin: 0.0,
                    cmax: 1.0,
                    value_label: "APE (m)".into(),
                }),
            }));
        }
        for (k, f) in figs.iter().enumerate() {
            let svg = super::super::style::render_svg(f).unwrap();
            assert!(svg.contains("<svg") && svg.len() > 1000, "figure {k}");
            let png = super::super::style::render_png(f).unwrap();
            assert!(png.len() > 1000, "figure {k}");
        }
    }
}

//! The sweep figure (`DIR/sweep.svg`): DE (median, RMSE) on the left axis and the discarded share on
//! the right against the swept value — the paper's ε_min figure; for a time-offset sweep, each
//! method's Δt as a vertical line.

use plotters::chart::DualCoordChartContext;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{label_font, legend, padded_range, plot_err, series_color, title_font, Draw};
use crate::error::Result;
use crate::eval::sweep::Sweep;

/// One curve family: an estimate at one window size.
#[derive(Debug, Clone, Default)]
pub struct SweepSeries {
    pub label: String,
    /// (value, DE median, DE RMSE, discarded fraction).
    pub points: Vec<(f64, Option<f64>, Option<f64>, f64)>,
}

/// The data of the figure.
#[derive(Debug, Clone, Default)]
pub struct SweepFigure {
    pub title: String,
    pub x_label: String,
    pub series: Vec<SweepSeries>,
    /// Vertical markers (label, value): each method's Δt.
    pub markers: Vec<(String, f64)>,
}

impl SweepFigure {
    /// The figure of a finished sweep.
    pub fn from_sweep(s: &Sweep, title: String) -> Self {
        let mut series: Vec<SweepSeries> = Vec::new();
        for r in &s.rows {
            let Some(m) = &r.metrics else { continue };
            let label = format!("{}, w = {} m", r.estimate, m.window_m);
            let key = if s.param == crate::eval::sweep::SweepParam::Window {
                r.estimate.clone()
            } else {
                label
            };
            let i = match series.iter().position(|x| x.label == key) {
                Some(i) => i,
                None => {
                    series.push(SweepSeries {
                        label: key,
                        points: Vec::new(),
                    });
                    series.len() - 1
                }
            };
            series[i]
                .points
                .push((r.value, m.de_median, m.de_rmse, m.discarded_fraction));
        }
        for x in &mut series {
            x.points.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        SweepFigure {
            title,
            x_label: s.param.axis_label().into(),
            series,
            markers: s
                .method_offsets
                .iter()
                .map(|m| {
                    (
                        format!("{} {}: Δt = {:+.3} s", m.estimate, m.method, m.offset_s),
                        m.offset_s,
                    )
                })
                .collect(),
        }
    }
}

impl Draw for SweepFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let pts = || self.series.iter().flat_map(|s| s.points.iter());
        let (x0, x1) = padded_range(pts().map(|p| p.0).chain(self.markers.iter().map(|m| m.1)));
        let (_, y1) = padded_range(pts().flat_map(|p| [p.1, p.2]).flatten().chain([0.0]));
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font())
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .right_y_label_area_size(70)
            .build_cartesian_2d(x0..x1, 0.0..y1)
            .map_err(plot_err)?
            .set_secondary_coord(x0..x1, 0.0..1.0);
        self.axes(&mut chart)?;
        let n = self.series.len();
        for (i, s) in self.series.iter().enumerate() {
            let c = series_color(i, n);
            let med = s.points.iter().filter_map(|p| Some((p.0, p.1?)));
            chart
                .draw_series(LineSeries::new(med, c.stroke_width(2)).point_size(3))
                .map_err(plot_err)?
                .label(format!("{}: DE median", s.label))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            let rmse: Vec<(f64, f64)> = s.points.iter().filter_map(|p| Some((p.0, p.2?))).collect();
            chart
                .draw_series(DashedLineSeries::new(rmse, 8, 5, c.stroke_width(2)))
                .map_err(plot_err)?
                .label(format!("{}: DE RMSE (dashed)", s.label))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 8, y)], c.stroke_width(2))
                });
            let disc: Vec<(f64, f64)> = s.points.iter().map(|p| (p.0, p.3)).collect();
            chart
                .draw_secondary_series(DottedLineSeries::new(disc, 2, 6, move |p| {
                    Circle::new(p, 2, c.filled())
                }))
                .map_err(plot_err)?
                .label(format!(
                    "{}: discarded fraction (dotted, right axis)",
                    s.label
                ))
                .legend(move |(x, y)| Circle::new((x + 10, y), 2, c.filled()));
        }
        self.draw_markers(&mut chart, y1)?;
        legend(&mut chart, SeriesLabelPosition::LowerRight)
    }
}

/// A chart with a second y axis, both on f64.
type Dual<'a, DB> = DualCoordChartContext<
    'a,
    DB,
    Cartesian2d<RangedCoordf64, RangedCoordf64>,
    Cartesian2d<RangedCoordf64, RangedCoordf64>,
>;

impl SweepFigure {
    /// Both y axes: DE on the left, the discarded fraction on the right.
    fn axes<'a, DB: DrawingBackend + 'a>(&self, chart: &mut Dual<'a, DB>) -> Result<()> {
        chart
            .configure_mesh()
            .x_desc(self.x_label.as_str())
            .y_desc("Drift Error (–)")
            .label_style(label_font())
            .axis_desc_style(label_font())
            .draw()
            .map_err(plot_err)?;
        chart
            .configure_secondary_axes()
            .y_desc("discarded fraction of the path (dotted)")
            .label_style(label_font())
            .axis_desc_style(label_font())
            .draw()
            .map_err(plot_err)?;
        Ok(())
    }

    /// Each method's Δt as a vertical line (time-offset sweeps).
    fn draw_markers<'a, DB: DrawingBackend + 'a>(
        &self,
        chart: &mut Dual<'a, DB>,
        y1: f64,
    ) -> Result<()> {
        let red = RGBColor(213, 94, 0);
        for (k, (label, x)) in self.markers.iter().enumerate() {
            let col = if k == 0 {
                red
            } else {
                series_color(k, self.markers.len() + 1)
            };
            chart
                .draw_series(DashedLineSeries::new(
                    [(*x, 0.0), (*x, y1)],
                    4,
                    4,
                    col.stroke_width(1),
                ))
                .map_err(plot_err)?
                .label(label.clone())
                .legend(move |(a, b)| {
                    PathElement::new(vec![(a, b - 6), (a, b + 6)], col.stroke_width(2))
                });
        }
        Ok(())
    }
}

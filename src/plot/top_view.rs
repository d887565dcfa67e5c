//! Top view: the reference and the aligned estimate in the horizontal plane, the estimate coloured by
//! the Drift Error of the window it lies in, samples in excluded intervals (turns in place, gaps)
//! marked. Equal scale on both axes, so the shape is true. The estimate is drawn after a rigid 2-D
//! fit onto the reference (display only; the legend says so). The estimate is drawn after a rigid 2-D
//! fit onto the reference (display only; the legend says so).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{
    label_font, legend, padded_range, plot_err, title_font, viridis, Chart, Draw, FAMILY,
    MAX_POINTS,
};
use crate::error::Result;

/// The data of a top view (metres, local frame; DE unitless).
#[derive(Debug, Clone, Default)]
pub struct TopView {
    pub title: String,
    /// Reference positions (x, y).
    pub reference: Vec<(f64, f64)>,
    /// Aligned estimate positions (x, y) and the DE of their window (`None`: in no window).
    pub estimate: Vec<(f64, f64, Option<f64>)>,
    /// Estimate positions inside an excluded interval.
    pub excluded: Vec<(f64, f64)>,
    /// The window size the colours belong to, metres.
    pub window_m: f64,
}

const BAR_W: u32 = 120;

impl TopView {
    /// DE mapped to the colour scale's top (the 95th percentile, so one outlier does not wash out the rest).
    fn de_top(&self) -> f64 {
        let mut v: Vec<f64> = self.estimate.iter().filter_map(|p| p.2).collect();
        v.sort_by(f64::total_cmp);
        match v.len() {
            0 => 1.0,
            n => v[((n - 1) as f64 * 0.95) as usize].max(1e-6),
        }
    }

    fn ranges(&self, px: (f64, f64)) -> ((f64, f64), (f64, f64)) {
        let xs = self
            .reference
            .iter()
            .map(|p| p.0)
            .chain(self.estimate.iter().map(|p| p.0));
        let ys = self
            .reference
            .iter()
            .map(|p| p.1)
            .chain(self.estimate.iter().map(|p| p.1));
        let (x0, x1) = padded_range(xs);
        let (y0, y1) = padded_range(ys);
        // Same metres per pixel on both axes.
        let m_per_px = ((x1 - x0) / px.0).max((y1 - y0) / px.1);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let (hx, hy) = (0.5 * m_per_px * px.0, 0.5 * m_per_px * px.1);
        ((cx - hx, cx + hx), (cy - hy, cy + hy))
    }
}

impl Draw for TopView {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (w, _) = root.dim_in_pixel();
        let (left, right) = root.split_horizontally(w - BAR_W);
        let (lw, lh) = left.dim_in_pixel();
        // Plot area: the figure less the caption, the label areas and margins.
        let px = (
            (lw as f64 - 70.0 - 20.0).max(10.0),
            (lh as f64 - 40.0 - 50.0 - 20.0).max(10.0),
        );
        let ((x0, x1), (y0, y1)) = self.ranges(px);
        let mut chart = ChartBuilder::on(&left)
            .caption(&self.title, title_font())
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .label_style(label_font())
            .axis_desc_style(label_font())
            .light_line_style(WHITE)
            .draw()
            .map_err(plot_err)?;
        let grey = RGBColor(150, 150, 150);
        let refs: Vec<(f64, f64)> = super::style::decimate(self.reference.len(), MAX_POINTS)
            .into_iter()
            .map(|i| self.reference[i])
            .collect();
        chart
            .draw_series(LineSeries::new(refs, grey.stroke_width(2)))
            .map_err(plot_err)?
            .label("reference")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(2))
            });
        let top = self.draw_estimate(&mut chart)?;
        legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        colour_bar(&right, top)
    }
}

impl TopView {
    /// The estimate coloured by DE, the no-window stretches and the excluded samples; returns the
    /// colour scale's top.
    fn draw_estimate<'a, DB: DrawingBackend + 'a>(&self, chart: &mut Chart<'a, DB>) -> Result<f64> {
        let top = self.de_top();
        let est: Vec<(f64, f64, Option<f64>)> =
            super::style::decimate(self.estimate.len(), MAX_POINTS)
                .into_iter()
                .map(|i| self.estimate[i])
                .collect();
        chart
            .draw_series(runs(&est).into_iter().map(|(de, pts)| {
                let c = match de {
                    Some(d) => viridis(d / top),
                    None => RGBColor(200, 200, 200),
                };
                PathElement::new(pts, c.stroke_width(4))
            }))
            .map_err(plot_err)?
            .label(format!(
                "aligned estimate, 2-D fit onto the reference (colour: DE, w = {} m)",
                self.window_m
            ))
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], viridis(0.5).stroke_width(4))
            });
        let pale = RGBColor(200, 200, 200);
        chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
            .map_err(plot_err)?
            .label("estimate in no window (gap, standstill)")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], pale.stroke_width(4))
            });
        let red = RGBColor(213, 94, 0);
        let ex: Vec<(f64, f64)> = super::style::decimate(self.excluded.len(), MAX_POINTS / 4)
            .into_iter()
            .map(|i| self.excluded[i])
            .collect();
        chart
            .draw_series(ex.iter().map(|&p| Cross::new(p, 4, red.stroke_width(1))))
            .map_err(plot_err)?
            .label("excluded (turn in place, gap)")
            .legend(move |(x, y)| Cross::new((x + 10, y), 4, red.stroke_width(1)));
        Ok(top)
    }
}

/// One window's stretch of the estimate: its DE and its points.
type Run = (Option<f64>, Vec<(f64, f64)>);

/// Consecutive points of one window as one polyline (a few hundred paths instead of thousands of
/// dots); each run starts at the previous run's last point so the line is unbroken.
fn runs(est: &[(f64, f64, Option<f64>)]) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    for &(x, y, de) in est {
        match out.last_mut() {
            Some((d, pts)) if *d == de => pts.push((x, y)),
            Some((_, pts)) => {
                let start = pts[pts.len() - 1];
                out.push((de, vec![start, (x, y)]));
            }
            None => out.push((de, vec![(x, y)])),
        }
    }
    out
}

/// A vertical viridis bar from DE 0 to `top` with five labels.
fn colour_bar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, top: f64) -> Result<()> {
    let (_, h) = area.dim_in_pixel();
    let (y0, y1) = (60i32, h as i32 - 60);
    let x = 10i32;
    let steps = 100i32;
    for k in 0..steps {
        let f = k as f64 / steps as f64;
        // Shared integer edges: step k ends where step k + 1 begins, no seam.
        let edge = |k: i32| y1 - ((y1 - y0) as f64 * k as f64 / steps as f64).round() as i32;
        let (ya, yb) = (edge(k + 1), edge(k));
        area.draw(&Rectangle::new(
            [(x, ya), (x + 24, yb)],
            viridis(f).filled(),
        ))
        .map_err(plot_err)?;
    }
    for k in 0..=4 {
        let f = k as f64 / 4.0;
        let y = y1 - ((y1 - y0) as f64 * f) as i32;
        let label = if k == 4 {
            format!("≥{:.3}", top)
        } else {
            format!("{:.3}", f * top)
        };
        area.draw(&Text::new(label, (x + 30, y - 7), label_font()))
            .map_err(plot_err)?;
    }
    area.draw(&Text::new("DE (–)", (x, y0 - 30), (FAMILY, 15).into_font()))
        .map_err(plot_err)
}

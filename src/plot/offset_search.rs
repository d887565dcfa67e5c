//! The offset search: each method's correlation against Δt around the answer, each method's peak
//! and the applied Δt marked, so a user sees how sharp and how unique the peak is.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::offset_curves::CorrelationCurve;
use super::style::{label_font, legend, padded_range, plot_err, series_color, title_font, Draw};
use crate::error::Result;

/// The data of the figure.
#[derive(Debug, Clone, Default)]
pub struct OffsetSearch {
    pub title: String,
    pub curves: Vec<CorrelationCurve>,
    /// The applied Δt, seconds (`None`: none applied, e.g. a weak answer).
    pub chosen_s: Option<f64>,
}

impl Draw for OffsetSearch {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let all = || self.curves.iter().flat_map(|c| c.points.iter());
        let (x0, x1) = padded_range(all().map(|p| p.0));
        let (y0, y1) = padded_range(all().map(|p| p.1).chain([0.0]));
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font())
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1.max(1.0_f64.min(y1 + 0.1)))
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("time offset Δt (s): t_est + Δt on the reference clock")
            .y_desc("normalised cross-correlation (–)")
            .label_style(label_font())
            .axis_desc_style(label_font())
            .draw()
            .map_err(plot_err)?;
        let n = self.curves.len();
        for (i, c) in self.curves.iter().enumerate() {
            let col = series_color(i, n);
            let label = match c.peak {
                Some((dt, r)) => format!("{}: peak {dt:+.3} s, NCC {r:.2}", c.method),
                None => format!("{}: failed", c.method),
            };
            chart
                .draw_series(LineSeries::new(
                    c.points.iter().copied(),
                    col.stroke_width(2),
                ))
                .map_err(plot_err)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2))
                });
            if let Some(p) = c.peak {
                chart
                    .draw_series([TriangleMarker::new(p, 7, col.filled())])
                    .map_err(plot_err)?;
            }
        }
        if let Some(dt) = self.chosen_s {
            let red = RGBColor(213, 94, 0);
            chart
                .draw_series(DashedLineSeries::new(
                    [(dt, y0), (dt, y1)],
                    6,
                    4,
                    red.stroke_width(2),
                ))
                .map_err(plot_err)?
                .label(format!("applied Δt = {dt:+.3} s"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], red.stroke_width(2))
                });
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight)
    }
}

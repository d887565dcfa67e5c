//! Drift Error per window along the travelled distance, one line per window size, each with its median
//! (dashed) and interquartile band (shaded): where along the mission the estimate drifts, and how
//! typical each window is.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{
    decimate, legend, padded_range, plot_err, series_color, xy_chart, Draw, MAX_POINTS,
};
use crate::error::Result;

/// One window size's windows.
#[derive(Debug, Clone, Default)]
pub struct DeSeries {
    pub window_m: f64,
    /// (distance along the reference at the window's middle, m; DE).
    pub points: Vec<(f64, f64)>,
    pub median: Option<f64>,
    pub q1: Option<f64>,
    pub q3: Option<f64>,
}

/// The data of the figure.
#[derive(Debug, Clone, Default)]
pub struct DriftAlong {
    pub title: String,
    pub series: Vec<DeSeries>,
}

impl Draw for DriftAlong {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let all = || self.series.iter().flat_map(|s| s.points.iter());
        let (x0, x1) = padded_range(all().map(|p| p.0));
        let (_, y1) = padded_range(all().map(|p| p.1).chain([0.0]));
        let mut chart = xy_chart(
            root,
            &self.title,
            ((x0, x1), (0.0, y1)),
            (
                "distance along the reference (m)",
                "Drift Error |1 − α·Δs_est/Δs_ref| (–)",
            ),
        )?;
        let n = self.series.len();
        for (i, s) in self.series.iter().enumerate() {
            let c = series_color(i, n);
            if let (Some(a), Some(b)) = (s.q1, s.q3) {
                chart
                    .draw_series([Rectangle::new([(x0, a), (x1, b)], c.mix(0.15).filled())])
                    .map_err(plot_err)?
                    .label(format!("IQR, w = {} m: [{a:.4}, {b:.4}]", s.window_m))
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 5), (x + 20, y + 5)], c.mix(0.25).filled())
                    });
            }
            if let Some(m) = s.median {
                chart
                    .draw_series(DashedLineSeries::new(
                        [(x0, m), (x1, m)],
                        8,
                        5,
                        c.stroke_width(2),
                    ))
                    .map_err(plot_err)?
                    .label(format!("median, w = {} m: {m:.4}", s.window_m))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 8, y), (x + 12, y), (x + 20, y)], c)
                    });
            }
            let pts: Vec<(f64, f64)> = decimate(s.points.len(), MAX_POINTS)
                .into_iter()
                .map(|k| s.points[k])
                .collect();
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(1)).point_size(2))
                .map_err(plot_err)?
                .label(format!("DE per window, w = {} m", s.window_m))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

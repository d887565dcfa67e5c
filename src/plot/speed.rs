//! Speed of the reference and of the aligned estimate over time: after alignment the two profiles
//! should lie on each other; a lag, a scale error or a dropout shows at a glance.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{
    decimate, legend, padded_range, plot_err, series_color, xy_chart, Draw, MAX_POINTS,
};
use crate::error::Result;

/// The data of the figure: (seconds from the reference's start, m/s).
#[derive(Debug, Clone, Default)]
pub struct SpeedFit {
    pub title: String,
    pub reference: Vec<(f64, f64)>,
    pub estimate: Vec<(f64, f64)>,
    /// A time step longer than this (after thinning) is a gap: the line is broken there, seconds.
    pub max_gap_s: f64,
}

/// The pieces of `p` between time gaps longer than `gap` (a GNSS outage is not drawn as a ramp).
fn split_at_gaps(p: &[(f64, f64)], gap: f64) -> Vec<&[(f64, f64)]> {
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..p.len() {
        if p[i].0 - p[i - 1].0 > gap {
            out.push(&p[start..i]);
            start = i;
        }
    }
    if start < p.len() {
        out.push(&p[start..]);
    }
    out
}

impl Draw for SpeedFit {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let all = || self.reference.iter().chain(self.estimate.iter());
        let (x0, x1) = padded_range(all().map(|p| p.0));
        let (_, y1) = padded_range(all().map(|p| p.1).chain([0.0]));
        let mut chart = xy_chart(
            root,
            &self.title,
            ((x0, x1), (0.0, y1)),
            (
                "time on the reference clock (s from its start)",
                "speed (m/s)",
            ),
        )?;
        let series = [
            ("reference", &self.reference, 0usize, 3u32),
            ("aligned estimate", &self.estimate, 1, 1),
        ];
        for (name, pts, i, w) in series {
            let c = series_color(i, 2);
            let p: Vec<(f64, f64)> = decimate(pts.len(), MAX_POINTS)
                .into_iter()
                .map(|k| pts[k])
                .collect();
            for (k, piece) in split_at_gaps(&p, self.max_gap_s).into_iter().enumerate() {
                let drawn = chart
                    .draw_series(LineSeries::new(piece.iter().copied(), c.stroke_width(w)))
                    .map_err(plot_err)?;
                if k == 0 {
                    drawn.label(name).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w))
                    });
                }
            }
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

//! Every source's clock against the reference over the mission, one line per source coloured by its
//! clock domain: sources of one domain lie on one line, a drift is a slope, a step a jump.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{legend, padded_range, plot_err, series_color, xy_chart, Draw};
use crate::error::Result;

/// One source's clock model sampled over its span.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceLine {
    pub name: String,
    /// Index of its domain (its colour).
    pub domain: usize,
    /// (t in s from the reference's start, Δt in ms).
    pub points: Vec<(f64, f64)>,
}

/// The data of the figure.
#[derive(Debug, Clone, PartialEq)]
pub struct ClockDomains {
    pub title: String,
    pub domains: usize,
    pub lines: Vec<SourceLine>,
}

impl Draw for ClockDomains {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let xs = self.lines.iter().flat_map(|l| l.points.iter().map(|p| p.0));
        let ys = self.lines.iter().flat_map(|l| l.points.iter().map(|p| p.1));
        let (x0, x1) = padded_range(xs);
        let (y0, y1) = padded_range(ys);
        let mut chart = xy_chart(
            root,
            &self.title,
            ((x0, x1), (y0, y1)),
            (
                "time on the reference clock (s from its start)",
                "clock offset Δt to the reference (ms)",
            ),
        )?;
        for l in &self.lines {
            let c = series_color(l.domain, self.domains.max(2));
            chart
                .draw_series(LineSeries::new(l.points.iter().copied(), c.stroke_width(3)))
                .map_err(plot_err)?
                .label(format!("{} (domain {})", l.name, l.domain + 1))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
                });
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

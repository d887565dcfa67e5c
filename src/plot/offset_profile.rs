//! The offset over time: Δt measured on pieces of the mission with its σ band, and the model chosen
//! for the whole mission (constant, drift, steps) drawn over it, so a drifting or stepping clock is
//! seen at once.
//!
//! The figure takes plain data ([`OffsetProfile`]) in the shape of the report's
//! `time_offset.profile` / `model` / `segments`; [`OffsetProfile::from_thirds`] builds it from what
//! the report holds today (the offsets of the first and last third).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{legend, padded_range, plot_err, series_color, xy_chart, Chart, Draw};
use crate::error::Result;
use crate::report::json::TimeOffsetReport;

/// One measurement of the offset on a piece of the mission (`time_offset.profile[]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfilePoint {
    /// Middle of the piece, seconds (any origin; the figure shows it as given).
    pub t: f64,
    pub offset_s: f64,
    pub sigma_s: Option<f64>,
    pub correlation: Option<f64>,
}

/// The clock model chosen for the mission (`time_offset.model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OffsetModel {
    Constant,
    Drift,
    Steps,
}

impl OffsetModel {
    pub fn as_str(self) -> &'static str {
        match self {
            OffsetModel::Constant => "constant",
            OffsetModel::Drift => "drift",
            OffsetModel::Steps => "steps",
        }
    }
}

/// A piece of the model: Δt from `offset_s` at `t_start` to `offset_end_s` at `t_end`
/// (`time_offset.segments[]`; constant and step pieces have both ends equal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub t_start: f64,
    pub t_end: f64,
    pub offset_s: f64,
    pub offset_end_s: f64,
    pub sigma_s: Option<f64>,
}

/// The data of the figure.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetProfile {
    pub title: String,
    pub points: Vec<ProfilePoint>,
    pub model: OffsetModel,
    pub segments: Vec<Segment>,
}

impl OffsetProfile {
    /// From today's report: the first- and last-third offsets (at the thirds' middles) and the applied
    /// Δt as a constant model over `[t_first, t_last]` (seconds from the reference's start).
    pub fn from_thirds(title: String, o: &TimeOffsetReport, t_first: f64, t_last: f64) -> Self {
        let span = t_last - t_first;
        let third = |t: f64, v: Option<f64>, s: Option<f64>| {
            v.map(|offset_s| ProfilePoint {
                t,
                offset_s,
                sigma_s: s,
                correlation: None,
            })
        };
        let points = [
            third(t_first + span / 6.0, o.first_third_s, o.first_third_sigma_s),
            third(
                t_first + 5.0 * span / 6.0,
                o.last_third_s,
                o.last_third_sigma_s,
            ),
        ]
        .into_iter()
        .flatten()
        .collect();
        OffsetProfile {
            title,
            points,
            model: OffsetModel::Constant,
            segments: vec![Segment {
                t_start: t_first,
                t_end: t_last,
                offset_s: o.applied_s,
                offset_end_s: o.applied_s,
                sigma_s: None,
            }],
        }
    }
}

impl Draw for OffsetProfile {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let sig = |s: Option<f64>| s.unwrap_or(0.0);
        let ts = self
            .points
            .iter()
            .map(|p| p.t)
            .chain(self.segments.iter().flat_map(|s| [s.t_start, s.t_end]));
        let (x0, x1) = padded_range(ts);
        let ys = self
            .points
            .iter()
            .flat_map(|p| [p.offset_s - sig(p.sigma_s), p.offset_s + sig(p.sigma_s)])
            .chain(
                self.segments
                    .iter()
                    .flat_map(|s| [s.offset_s, s.offset_end_s]),
            );
        let (y0, y1) = padded_range(ys);
        let (y0, y1) = (
            y0.min(0.5 * (y0 + y1) - 0.01),
            y1.max(0.5 * (y0 + y1) + 0.01),
        );
        let mut chart = xy_chart(
            root,
            &self.title,
            ((x0, x1), (y0, y1)),
            (
                "time on the reference clock (s from its start)",
                "time offset Δt (s)",
            ),
        )?;
        self.draw_measurements(&mut chart)?;
        self.draw_model(&mut chart)?;
        legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

impl OffsetProfile {
    /// The σ band and the measured points with their ±σ bars.
    fn draw_measurements<'a, DB: DrawingBackend + 'a>(
        &self,
        chart: &mut Chart<'a, DB>,
    ) -> Result<()> {
        let sig = |s: Option<f64>| s.unwrap_or(0.0);
        let c = series_color(0, 2);
        if self.points.len() >= 2 {
            let mut band: Vec<(f64, f64)> = self
                .points
                .iter()
                .map(|p| (p.t, p.offset_s + sig(p.sigma_s)))
                .collect();
            band.extend(
                self.points
                    .iter()
                    .rev()
                    .map(|p| (p.t, p.offset_s - sig(p.sigma_s))),
            );
            chart
                .draw_series([Polygon::new(band, c.mix(0.2).filled())])
                .map_err(plot_err)?
                .label("±σ band")
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 20, y + 5)], c.mix(0.3).filled())
                });
        }
        chart
            .draw_series(self.points.iter().map(|p| {
                let s = sig(p.sigma_s);
                ErrorBar::new_vertical(
                    p.t,
                    p.offset_s - s,
                    p.offset_s,
                    p.offset_s + s,
                    c.filled().stroke_width(2),
                    10,
                )
            }))
            .map_err(plot_err)?
            .label("Δt measured on a piece of the mission (±σ)")
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
        Ok(())
    }

    /// The chosen model, one line per segment.
    fn draw_model<'a, DB: DrawingBackend + 'a>(&self, chart: &mut Chart<'a, DB>) -> Result<()> {
        let m = series_color(1, 2);
        let model = self.model.as_str();
        for (k, s) in self.segments.iter().enumerate() {
            let series = chart
                .draw_series(LineSeries::new(
                    [(s.t_start, s.offset_s), (s.t_end, s.offset_end_s)],
                    m.stroke_width(3),
                ))
                .map_err(plot_err)?;
            if k == 0 {
                series
                    .label(format!("model: {model} (applied)"))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], m.stroke_width(3))
                    });
            }
        }
        Ok(())
    }
}

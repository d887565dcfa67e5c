//! The offset over time: Δt measured on pieces of the mission with its σ band, and the model chosen
//! for the whole mission (constant, drift, steps) drawn over it, so a drifting or stepping clock is
//! seen at once.
//!
//! The figure takes plain data ([`OffsetProfile`]); [`OffsetProfile::from_report`] builds it from the
//! report's `time_offset.profile` / `model` / `segments`.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{legend, padded_range, plot_err, series_color, xy_chart, Chart, Draw};
use crate::align::clock_model::OffsetModel;
use crate::clock::ClockCorrection;
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
    /// From the report's `time_offset`: its profile windows, and the chosen model drawn over
    /// `[t_first, t_last]`. Times are shown in seconds from `t0` (the reference's first stamp, the
    /// report's times are absolute). A linear model is drawn as the clock correction applies it
    /// ([`ClockCorrection`], the report's `t_mid` and drift).
    pub fn from_report(
        title: String,
        o: &TimeOffsetReport,
        t0: f64,
        (t_first, t_last): (f64, f64),
    ) -> Self {
        let points = o
            .profile
            .iter()
            .map(|p| ProfilePoint {
                t: p.t - t0,
                offset_s: p.offset_s,
                sigma_s: Some(p.sigma_s),
                correlation: Some(p.correlation),
            })
            .collect::<Vec<_>>();
        let model = o.model.unwrap_or(OffsetModel::Constant);
        let flat = |t_start: f64, t_end: f64, offset_s: f64, sigma_s: Option<f64>| Segment {
            t_start,
            t_end,
            offset_s,
            offset_end_s: offset_s,
            sigma_s,
        };
        let segments = match model {
            OffsetModel::Piecewise if !o.segments.is_empty() => o
                .segments
                .iter()
                .map(|s| flat(s.t_start - t0, s.t_end - t0, s.offset_s, Some(s.sigma_s)))
                .collect(),
            OffsetModel::Linear => {
                // The model as the estimate's stamps were corrected by it (the report's t_mid).
                let c = ClockCorrection::from_report(o);
                let at = |t: f64| c.offset_at_s(t + t0).unwrap_or(o.applied_s);
                vec![Segment {
                    t_start: t_first,
                    t_end: t_last,
                    offset_s: at(t_first),
                    offset_end_s: at(t_last),
                    sigma_s: o.sigma_s,
                }]
            }
            _ => vec![flat(t_first, t_last, o.applied_s, o.sigma_s)],
        };
        OffsetProfile {
            title,
            points,
            model,
            segments,
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

//! The distribution of Drift Error across a batch's missions (`summary.html`): per estimate and window
//! size, every mission's DE RMSE as a dot over its interquartile box and median.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{category_chart, padded_range, plot_err, series_color, Draw};
use crate::error::Result;

/// The data: (label, each mission's DE RMSE).
#[derive(Debug, Clone, Default)]
pub struct DeDistribution {
    pub title: String,
    pub groups: Vec<(String, Vec<f64>)>,
}

impl Draw for DeDistribution {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let n = self.groups.len().max(1);
        let (_, y1) = padded_range(
            self.groups
                .iter()
                .flat_map(|g| g.1.iter().copied())
                .chain([0.0]),
        );
        let labels: Vec<String> = self.groups.iter().map(|g| g.0.clone()).collect();
        let mut chart = category_chart(
            root,
            &self.title,
            &labels,
            (0.0, y1),
            ("estimate, window size", "DE RMSE per mission (–)"),
            70,
        )?;
        for (i, (_, v)) in self.groups.iter().enumerate() {
            let c = series_color(i, n);
            let x = i as f64;
            let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
            if s.is_empty() {
                continue;
            }
            s.sort_by(f64::total_cmp);
            let (q1, med, q3) = (
                crate::stats::quantile_sorted(&s, 0.25),
                crate::stats::quantile_sorted(&s, 0.5),
                crate::stats::quantile_sorted(&s, 0.75),
            );
            chart
                .draw_series([Rectangle::new(
                    [(x - 0.25, q1), (x + 0.25, q3)],
                    c.mix(0.2).filled(),
                )])
                .map_err(plot_err)?;
            chart
                .draw_series([PathElement::new(
                    vec![(x - 0.25, med), (x + 0.25, med)],
                    c.stroke_width(3),
                )])
                .map_err(plot_err)?;
            let m = s.len().max(2) as f64;
            chart
                .draw_series(v.iter().enumerate().map(|(k, &y)| {
                    // Spread the dots sideways in mission order so equal values stay visible.
                    let dx = 0.2 * (k as f64 / (m - 1.0) - 0.5);
                    Circle::new((x + dx, y), 4, c.filled())
                }))
                .map_err(plot_err)?;
        }
        Ok(())
    }
}

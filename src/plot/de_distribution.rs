//! The distribution of Drift Error across a batch's missions (`summary.html`): per estimate and window
//! size, every mission's DE RMSE as a dot over its interquartile box and median.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{label_font, padded_range, plot_err, series_color, title_font, Draw};
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
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font())
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..(n as f64 - 0.5), 0.0..y1)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_labels(n)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 {
                    labels.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .x_desc("estimate, window size")
            .y_desc("DE RMSE per mission (–)")
            .label_style(label_font())
            .axis_desc_style(label_font())
            .disable_x_mesh()
            .draw()
            .map_err(plot_err)?;
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

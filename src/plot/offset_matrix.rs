//! The offset matrix of a mission's sources as a heat map: cell (A, B) is Δt_AB in ms (B's stamps
//! onto A's clock), its colour |Δt| in units of its σ (viridis, dark = the same clock within 1σ,
//! bright = 10σ and more), so clock domains show as dark blocks. A clock that is not constant is
//! starred; a pair never measured is blank.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::style::{label_font, plot_err, title_font, viridis, Draw};
use crate::error::Result;

/// One cell: Δt in ms, its σ in ms, and whether the pair's clock is constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    pub offset_ms: f64,
    pub sigma_ms: Option<f64>,
    pub constant: bool,
}

/// The data of the figure.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetMatrix {
    pub title: String,
    pub names: Vec<String>,
    /// Row A, column B.
    pub cells: Vec<Vec<Option<Cell>>>,
}

impl OffsetMatrix {
    /// The colour scale: |Δt|/σ over 10, clamped (a missing σ counts as far).
    fn shade(c: &Cell) -> f64 {
        match c.sigma_ms {
            Some(s) if s > 0.0 => (c.offset_ms.abs() / s / 10.0).min(1.0),
            _ => 1.0,
        }
    }
}

impl Draw for OffsetMatrix {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let n = self.names.len().max(1);
        let (w, h) = root.dim_in_pixel();
        let left = 170i32;
        let top = 60i32;
        let size = (((w as i32 - left - 20).min(h as i32 - top - 60)) / n as i32).max(10);
        root.draw(&Text::new(self.title.clone(), (10, 10), title_font()))
            .map_err(plot_err)?;
        root.draw(&Text::new(
            "row A, column B: Δt_AB in ms (B's stamps + Δt = A's clock); colour |Δt|/σ, dark = same clock; * not constant",
            (10, 36),
            label_font(),
        ))
        .map_err(plot_err)?;
        for (i, name) in self.names.iter().enumerate() {
            let short: String = name.chars().take(20).collect();
            let y = top + i as i32 * size + size / 2 - 8;
            root.draw(&Text::new(short.clone(), (10, y), label_font()))
                .map_err(plot_err)?;
            let x = left + i as i32 * size + 4;
            let label: String = short.chars().take((size / 9).max(3) as usize).collect();
            root.draw(&Text::new(
                label,
                (x, top + n as i32 * size + 8),
                label_font(),
            ))
            .map_err(plot_err)?;
        }
        for (i, row) in self.cells.iter().enumerate() {
            for (j, cell) in row.iter().enumerate() {
                let (x0, y0) = (left + j as i32 * size, top + i as i32 * size);
                let rect = [(x0, y0), (x0 + size - 2, y0 + size - 2)];
                let Some(c) = cell else {
                    root.draw(&Rectangle::new(rect, RGBColor(235, 235, 235).filled()))
                        .map_err(plot_err)?;
                    continue;
                };
                let f = Self::shade(c);
                root.draw(&Rectangle::new(rect, viridis(f).filled()))
                    .map_err(plot_err)?;
                let text = format!("{:+.1}{}", c.offset_ms, if c.constant { "" } else { "*" });
                let colour = if f < 0.6 { WHITE } else { BLACK };
                root.draw(&Text::new(
                    text,
                    (x0 + 4, y0 + size / 2 - 8),
                    label_font().color(&colour),
                ))
                .map_err(plot_err)?;
            }
        }
        Ok(())
    }
}

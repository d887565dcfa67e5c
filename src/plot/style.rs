//! What every figure shares: the embedded font, sizes, the colour-blind-safe viridis map, the
//! rendering of a figure to SVG text or PNG bytes, and the decimation that bounds what is drawn.
//!
//! The font (DejaVu Sans, Bitstream Vera licence, `assets/fonts/`) is compiled into the binary and
//! registered with plotters' `ab_glyph` text backend, so PNGs need no system font; SVG text names the
//! generic `sans-serif` family and is laid out with the same metrics.

use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{Error, Result};

/// DejaVu Sans (see `assets/fonts/DejaVuSans.LICENSE`).
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// The family every figure's text uses.
pub const FAMILY: &str = "sans-serif";
/// Figure size in pixels (readable at 100 % zoom on a laptop screen).
pub const SIZE: (u32, u32) = (960, 560);
/// Most points drawn per series: a 2-hour mission's figure stays well under 2 MB of SVG.
pub const MAX_POINTS: usize = 2500;

/// How figures are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlotFormat {
    Svg,
    Png,
}

impl PlotFormat {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            PlotFormat::Svg => "svg",
            PlotFormat::Png => "png",
        }
    }
}

/// Something that draws itself on any plotters backend (SVG text or an RGB bitmap).
pub trait Draw {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>;
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are ours and valid; a failure would show as missing text, not a crash.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
        let _ = plotters::style::register_font(FAMILY, FontStyle::Bold, FONT);
    });
}

/// Maps any plotters error to ours.
pub fn plot_err<E: std::fmt::Debug>(e: E) -> Error {
    Error::InvalidArgument(format!("drawing a figure failed: {e:?}"))
}

/// Renders `figure` as SVG text.
pub fn render_svg(figure: &impl Draw) -> Result<String> {
    register_font();
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        figure.draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    // Names in titles and legends come from the data: the document must stay valid XML.
    Ok(crate::report::escape::xml(&s).into_owned())
}

/// Renders `figure` as PNG bytes (an RGB bitmap drawn in memory, encoded with the `png` crate), for
/// the one file writer ([`crate::output::write_output`]).
pub fn render_png(figure: &impl Draw) -> Result<Vec<u8>> {
    register_font();
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        figure.draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder
            .write_header()
            .and_then(|mut writer| writer.write_image_data(&rgb))
            .map_err(plot_err)?;
    }
    Ok(out)
}

/// Viridis at `f` in [0, 1] (clamped).
pub fn viridis(f: f64) -> RGBColor {
    let f = if f.is_finite() {
        f.clamp(0.0, 1.0)
    } else {
        0.0
    };
    ViridisRGB.get_color(f as f32)
}

/// `n` distinct viridis colours for series (avoiding the palest yellow, hard to see on white).
pub fn series_color(i: usize, n: usize) -> RGBColor {
    if n <= 1 {
        return viridis(0.25);
    }
    viridis(0.85 * i as f64 / (n - 1) as f64)
}

/// Text style of titles.
pub fn title_font() -> TextStyle<'static> {
    (FAMILY, 20).into_font().color(&BLACK)
}

/// Text style of axis labels, ticks and legends.
pub fn label_font() -> TextStyle<'static> {
    (FAMILY, 15).into_font().color(&BLACK)
}

/// A chart on f64 axes.
pub type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A titled chart over `x` × `y` with labelled axes, the frame every figure shares.
pub fn xy_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    (x, y): ((f64, f64), (f64, f64)),
    (x_desc, y_desc): (&str, &str),
) -> Result<Chart<'a, DB>> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, title_font())
        .margin(10)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(label_font())
        .axis_desc_style(label_font())
        .draw()
        .map_err(plot_err)?;
    Ok(chart)
}

/// The category a category axis's tick at `v` names: its index where `v` is a whole number at or
/// above 0, none between categories.
pub fn category_at(v: f64) -> Option<usize> {
    let i = v.round();
    ((v - i).abs() < 1e-6 && i >= 0.0).then_some(i as usize)
}

/// A titled chart with one category per label along x (at 0, 1, …, named by `labels`) over `y`, the
/// frame of box and violin plots; `y_label_area` is the width left for the y ticks, in pixels.
pub fn category_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    labels: &[String],
    y: (f64, f64),
    (x_desc, y_desc): (&str, &str),
    y_label_area: u32,
) -> Result<Chart<'a, DB>> {
    let n = labels.len().max(1);
    let mut chart = ChartBuilder::on(root)
        .caption(title, title_font())
        .margin(10)
        .x_label_area_size(50)
        .y_label_area_size(y_label_area)
        .build_cartesian_2d(-0.5..(n as f64 - 0.5), y.0..y.1)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_labels(n)
        .x_label_formatter(&|x| {
            category_at(*x)
                .and_then(|i| labels.get(i).cloned())
                .unwrap_or_default()
        })
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(label_font())
        .axis_desc_style(label_font())
        .disable_x_mesh()
        .draw()
        .map_err(plot_err)?;
    Ok(chart)
}

/// The legend box of `chart` at `pos`, on a 2-D chart or a 3-D one alike.
pub fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    pos: SeriesLabelPosition,
) -> Result<()> {
    chart
        .configure_series_labels()
        .label_font(label_font())
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(pos)
        .draw()
        .map_err(plot_err)
}

/// Indices of at most `max` of `n` items, evenly spaced, the first and last always kept.
pub fn decimate(n: usize, max: usize) -> Vec<usize> {
    if n <= max || max < 2 {
        return (0..n).collect();
    }
    let step = (n - 1) as f64 / (max - 1) as f64;
    let mut v: Vec<usize> = (0..max)
        .map(|k| (k as f64 * step).round() as usize)
        .collect();
    v.dedup();
    v
}

/// `[lo, hi]` of the finite values, widened by 5 % (and to a unit span when flat).
pub fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 {
        return (lo - 0.5, hi + 0.5);
    }
    (lo - 0.05 * span, hi + 0.05 * span)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimate_keeps_ends_and_bound() {
        let v = decimate(100_000, 2500);
        assert_eq!(v.len(), 2500);
        assert_eq!((v[0], *v.last().unwrap()), (0, 99_999));
        assert_eq!(decimate(10, 2500), (0..10).collect::<Vec<_>>());
    }

    #[test]
    fn padded_range_handles_flat_and_empty() {
        assert_eq!(padded_range([1.0, 1.0].into_iter()), (0.5, 1.5));
        assert_eq!(padded_range(std::iter::empty()), (0.0, 1.0));
    }
}

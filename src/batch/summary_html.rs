//! `summary.html`: a batch at a glance — one row per mission × estimate × window with a link to the
//! mission's own report (`<mission>.html` when written, else its JSON), failed missions, and the
//! distribution of Drift Error across missions, inline like every trajdrift HTML page.

use std::fmt::Write;
use std::path::Path;

use super::summary::Summary;
use crate::plot::de_distribution::DeDistribution;
use crate::plot::style::render_svg;
use crate::render::html::page;
use crate::report::escape::html as escape;

/// The page for `summary`, whose per-mission files are in `dir`.
pub fn render(summary: &Summary, dir: &Path) -> String {
    let mut b = String::from("<h1>trajdrift batch summary</h1>\n");
    if summary.partial {
        b.push_str("<div class=\"warn\"><p><b>Partial</b>: merged from an incomplete or inconsistent set of results:</p><ul>");
        for p in &summary.problems {
            let _ = write!(b, "<li>{}</li>", escape(p));
        }
        b.push_str("</ul></div>\n");
    }
    let _ = writeln!(
        b,
        "<p>{} missions, {} failed, {} with a warning ({} with a weak offset).</p>",
        summary.missions,
        summary.failed.len(),
        summary.warned.len(),
        summary.weak.len()
    );
    distribution_figure(&mut b, summary);
    missions_table(&mut b, summary, dir);
    if !summary.warned.is_empty() {
        b.push_str("<h2>Missions with a warning</h2>\n");
        for w in &summary.warned {
            let _ = writeln!(
                b,
                "<p class=\"warn\">{}: {}</p>",
                escape(&w.mission),
                escape(&w.warnings.join(", "))
            );
        }
    }
    if !summary.failed.is_empty() {
        b.push_str("<h2>Failed missions</h2>\n");
        for f in &summary.failed {
            let _ = writeln!(
                b,
                "<p class=\"warn\">{}: {}</p>",
                escape(&f.mission),
                escape(&f.error)
            );
        }
    }
    page("trajdrift batch summary", &b)
}

/// The box plot of each estimate's DE RMSE across missions (left out when it cannot be drawn).
fn distribution_figure(b: &mut String, summary: &Summary) {
    let figure = DeDistribution {
        title: "Drift Error across missions".into(),
        groups: summary
            .estimates
            .iter()
            .map(|e| {
                (
                    format!("{}, {} m", e.estimate, e.window_m),
                    e.missions.iter().filter_map(|m| m.de_rmse).collect(),
                )
            })
            .collect(),
    };
    if let Ok(svg) = render_svg(&figure) {
        let _ = writeln!(b, "<figure>{svg}<figcaption>DE RMSE of each mission; box: interquartile range, bar: median.</figcaption></figure>");
    }
}

/// One row per mission and estimate, linked to the mission's own report.
fn missions_table(b: &mut String, summary: &Summary, dir: &Path) {
    b.push_str("<h2>Missions</h2>\n<table><tr><th>mission</th><th>estimate</th><th>w (m)</th><th>Δt (s)</th><th>offset</th><th>confidence</th><th>DE RMSE</th><th>report</th></tr>\n");
    let link = |mission: &str| {
        // A name that is not a safe file name (it came from a JSON file) gets no link.
        if !super::manifest::valid_name(mission) {
            return "–".to_string();
        }
        let html = format!("{mission}.html");
        let target = if dir.join(&html).exists() {
            html
        } else {
            format!("{mission}.json")
        };
        format!("<a href=\"{}\">{}</a>", escape(&target), escape(&target))
    };
    let num = |v: Option<f64>, d: usize| v.map_or("–".into(), |x| format!("{x:.d$}"));
    for e in &summary.estimates {
        for m in &e.missions {
            let _ = writeln!(
                b,
                "<tr><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{:+.4}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td></tr>",
                escape(&m.mission),
                escape(&e.estimate),
                e.window_m,
                m.dt_s,
                escape(m.offset_status.as_str()),
                num(m.confidence, 2),
                num(m.de_rmse, 4),
                link(&m.mission)
            );
        }
    }
    b.push_str("</table>\n");
}

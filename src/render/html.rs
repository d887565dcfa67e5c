//! The self-contained HTML report (`--html FILE`, and a batch's per-mission pages and `summary.html`):
//! one file with the figures inline as SVG and the style inline, no script and nothing loaded from the
//! network, so it opens offline and survives being attached to an email.

use std::fmt::Write;

use crate::report::escape::html as escape;
use crate::report::json::{EstimateReport, Report};

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em auto;max-width:1000px;color:#222;padding:0 1em}\
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}\
table{border-collapse:collapse;margin:.5em 0;font-size:.9em}td,th{border:1px solid #ccc;padding:.25em .6em;text-align:left}\
th{background:#f0f0f0}td.n{text-align:right;font-variant-numeric:tabular-nums}\
.warn{background:#fff4e0;border-left:4px solid #d55e00;padding:.5em 1em;margin:.4em 0}\
.ok{background:#eef7ee;border-left:4px solid #009e73;padding:.5em 1em}\
figure{margin:1em 0}figure svg{max-width:100%;height:auto;border:1px solid #ddd}figcaption{font-size:.9em;color:#555}";

/// A page with `title` and `body` (already HTML).
pub fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
<title>{}</title><style>{STYLE}</style></head><body>\n{body}\n</body></html>\n",
        escape(title)
    )
}

/// An SVG figure to inline, with its caption.
pub struct InlineFigure<'a> {
    pub title: &'a str,
    pub svg: &'a str,
}

/// The SVG element of `svg` without any XML prologue, for inlining.
pub fn svg_element(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

fn num(v: Option<f64>, digits: usize) -> String {
    v.filter(|x| x.is_finite())
        .map_or("–".into(), |x| format!("{x:.digits$}"))
}

/// A table with a header row; cells that start like a number are right-aligned.
pub fn table(head: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = String::from("<table><tr>");
    for h in head {
        let _ = write!(s, "<th>{}</th>", escape(h));
    }
    s.push_str("</tr>");
    for r in rows {
        s.push_str("<tr>");
        for c in r {
            let numeric = c.starts_with([
                '-', '+', '0', '1', '2', '3', '4', '5', '6', '7', '8', '9', '–',
            ]);
            let class = if numeric { " class=\"n\"" } else { "" };
            let _ = write!(s, "<td{class}>{}</td>", escape(c));
        }
        s.push_str("</tr>");
    }
    s.push_str("</table>\n");
    s
}

fn parameter_card(r: &Report) -> String {
    use crate::params::Word;
    let p = &r.parameters;
    let rows = vec![
        vec!["platform".into(), p.platform.word().to_string()],
        vec!["ε curvature (m)".into(), num(Some(p.curvature_eps_m), 3)],
        vec!["ε path (m)".into(), num(Some(p.path_eps_m), 3)],
        vec!["θ_max (rad)".into(), num(Some(p.theta_max_rad), 3)],
        vec!["Δt_max gaps (s)".into(), num(Some(p.dt_max_s), 2)],
        vec!["Δt_max curvature (s)".into(), num(p.curvature_dt_max_s, 2)],
        vec![
            "windows (m)".into(),
            p.windows_m
                .iter()
                .map(|w| w.to_string())
                .collect::<Vec<_>>()
                .join(", "),
        ],
        vec!["overlap".into(), num(Some(p.overlap), 2)],
        vec![
            "lever correction".into(),
            p.lever_correction.word().to_string(),
        ],
        vec!["lever arm a (m)".into(), num(Some(p.lever_arm_m), 3)],
        vec!["offset method".into(), p.offset_method.to_string()],
        vec!["max offset (s)".into(), num(Some(p.max_offset_s), 1)],
        vec!["stamp".into(), p.stamp.word().to_string()],
        vec!["reference noise σ (m)".into(), num(p.reference_noise_m, 4)],
    ];
    let mut s = String::from("<h2>Parameters</h2>\n");
    if let Some(a) = &p.auto {
        let _ = write!(
            s,
            "<p>Measured on the reference (<code>--platform auto</code>): {}.</p>",
            escape(&a.chosen.join(", "))
        );
    }
    s + &table(&["parameter", "value"], &rows)
}

fn offset_section(e: &EstimateReport) -> String {
    let o = &e.time_offset;
    let mut s = format!("<h3>{} — time offset</h3>\n", escape(&e.name));
    let _ = writeln!(
        s,
        "<p>Applied Δt = <b>{:+.4} s</b> ({}, status {}). {}</p>",
        o.applied_s,
        escape(o.method.as_str()),
        escape(o.status.as_str()),
        escape(o.reason.as_deref().unwrap_or(""))
    );
    let rows: Vec<Vec<String>> = o
        .methods
        .iter()
        .map(|m| {
            vec![
                m.method.to_string(),
                m.offset_s.map_or("–".into(), |x| format!("{x:+.4}")),
                num(m.correlation, 3),
                num(m.confidence, 2),
                num(m.margin, 3),
                num(m.defined_fraction, 2),
                m.status.to_string(),
                m.error.clone().unwrap_or_default(),
            ]
        })
        .collect();
    if !rows.is_empty() {
        s += &table(
            &[
                "method",
                "Δt (s)",
                "peak NCC",
                "confidence",
                "margin",
                "defined share",
                "status",
                "error",
            ],
            &rows,
        );
    }
    if let Some(m) = o.model {
        let _ = writeln!(
            s,
            "<p>Clock model: {} ({}), from {} profile windows{}.</p>",
            m.as_str(),
            escape(o.model_reason.as_deref().unwrap_or("")),
            o.profile.len(),
            o.drift_measured_ppm
                .map_or(String::new(), |p| format!("; linear fit {p:+.0} ppm"))
        );
    }
    s
}

fn drift_section(r: &Report) -> String {
    let rows: Vec<Vec<String>> = r
        .estimates
        .iter()
        .flat_map(|e| {
            e.drift_error.iter().map(move |d| {
                vec![
                    e.name.clone(),
                    d.window_m.to_string(),
                    d.windows.to_string(),
                    num(d.rmse, 4),
                    num(d.mean, 4),
                    num(d.median, 4),
                    num(d.std, 4),
                    num(d.q1, 4),
                    num(d.q3, 4),
                    num(d.p95, 4),
                    num(Some(d.discarded_fraction), 3),
                    d.lever_correction.as_str().to_string(),
                    num(d.scale, 4),
                    num(d.lateral_lever_m, 3),
                ]
            })
        })
        .collect();
    String::from("<h2>Drift Error</h2>\n")
        + &table(
            &[
                "estimate",
                "w (m)",
                "windows",
                "RMSE",
                "mean",
                "median",
                "std",
                "Q1",
                "Q3",
                "P95",
                "discarded",
                "lever corr.",
                "scale",
                "lateral lever (m)",
            ],
            &rows,
        )
}

/// The whole report of one evaluation, figures inline.
pub fn render_report(r: &Report, figures: &[InlineFigure<'_>]) -> String {
    let mut b = format!(
        "<h1>trajdrift report — {}</h1>\n<p>{} {} · reference <code>{}</code> ({} samples) · {} estimate(s)</p>\n",
        escape(&r.input.path),
        escape(&r.tool.name),
        escape(&r.tool.version),
        escape(&r.reference.topic),
        r.reference.samples,
        r.estimates.len()
    );
    b.push_str("<h2>Warnings</h2>\n");
    if r.warnings.is_empty() {
        b.push_str("<p class=\"ok\">No warning: every offset was found with confidence.</p>\n");
    }
    for w in &r.warnings {
        let _ = writeln!(b, "<p class=\"warn\">{}</p>", escape(&w.message));
    }
    b += &parameter_card(r);
    b.push_str("<h2>Time offset</h2>\n");
    for e in &r.estimates {
        b += &offset_section(e);
    }
    b += &drift_section(r);
    if !figures.is_empty() {
        b.push_str("<h2>Figures</h2>\n");
    }
    for f in figures {
        let _ = writeln!(
            b,
            "<figure>{}<figcaption>{}</figcaption></figure>",
            svg_element(f.svg),
            escape(f.title)
        );
    }
    page(&format!("trajdrift — {}", r.input.path), &b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
    }

    #[test]
    fn svg_prologue_is_dropped() {
        assert_eq!(svg_element("<?xml version=\"1.0\"?>\n<svg a>"), "<svg a>");
    }
}

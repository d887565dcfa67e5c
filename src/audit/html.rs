//! The audit as a self-contained HTML page (`trajdrift audit --html FILE`): the sources table, the
//! offset matrix as a heat map, every source's clock over the mission coloured by clock domain, the
//! closure of every triple, the domains, and each source's offset profile — the evaluation's page
//! style and figures ([`crate::render::html`], [`crate::plot`]), nothing loaded from the network.

use std::fmt::Write;

use super::report::AuditReport;
use super::table::describe_clock;
use crate::error::Result;
use crate::plot::clock_domains::{ClockDomains, SourceLine};
use crate::plot::offset_matrix::{Cell, OffsetMatrix};
use crate::plot::offset_profile::OffsetProfile;
use crate::plot::style::render_svg;
use crate::render::html::{page, svg_element, table};
use crate::report::escape::html as escape;

fn figure(svg: &str, caption: &str) -> String {
    format!(
        "<figure>{}<figcaption>{}</figcaption></figure>\n",
        svg_element(svg),
        escape(caption)
    )
}

/// The offset matrix's data.
pub fn offset_matrix(a: &AuditReport) -> OffsetMatrix {
    let names: Vec<String> = a.sources.iter().map(|s| s.name.clone()).collect();
    let cells = names
        .iter()
        .enumerate()
        .map(|(i, row)| {
            names
                .iter()
                .enumerate()
                .map(|(j, col)| {
                    if i == j {
                        return Some(Cell {
                            offset_ms: 0.0,
                            sigma_ms: Some(1.0),
                            constant: true,
                        });
                    }
                    let (x, y, sign) = if i < j {
                        (row, col, 1.0)
                    } else {
                        (col, row, -1.0)
                    };
                    a.pairs
                        .iter()
                        .find(|p| &p.a == x && &p.b == y)
                        .map(|p| Cell {
                            offset_ms: sign * p.clock.offset_s * 1e3,
                            sigma_ms: p.clock.sigma_s.map(|s| s * 1e3),
                            constant: p.clock.is_constant(),
                        })
                })
                .collect()
        })
        .collect();
    OffsetMatrix {
        title: "Pairwise clock offsets".into(),
        names,
        cells,
    }
}

/// Every source's clock model, sampled over its coverage (t from `t0`), coloured by domain.
pub fn clock_lines(a: &AuditReport, t0: f64) -> ClockDomains {
    let lines = a
        .sources
        .iter()
        .map(|s| {
            let c = s.clock.correction();
            let (t_start, t_end) = (s.coverage.t_start, s.coverage.t_end);
            let n = 200;
            let points = (0..=n)
                .filter_map(|k| {
                    let t = t_start + (t_end - t_start) * k as f64 / n as f64;
                    let dt = if s.reference {
                        Some(0.0)
                    } else {
                        c.offset_at_s(t)
                    };
                    dt.map(|d| (t - t0, d * 1e3))
                })
                .collect();
            SourceLine {
                name: s.name.clone(),
                domain: a
                    .domains
                    .iter()
                    .position(|d| d.name == s.domain)
                    .unwrap_or(0),
                points,
            }
        })
        .collect();
    ClockDomains {
        title: "Each source's clock against the reference, by clock domain".into(),
        domains: a.domains.len(),
        lines,
    }
}

/// The page.
pub fn render(a: &AuditReport) -> Result<String> {
    let t0 = a.sources.first().map_or(0.0, |r| r.coverage.t_start);
    let mut b = head_and_warnings(a);
    b += &sources_table(a, t0);
    b += &domains_section(a, t0)?;
    b += &closure_table(a);
    b += &profiles(a, t0)?;
    Ok(page(
        &format!("trajdrift audit — {}", a.inputs.join(" ")),
        &b,
    ))
}

/// The title line, the warnings and the sources out of line.
fn head_and_warnings(a: &AuditReport) -> String {
    let mut b = format!(
        "<h1>trajdrift audit — {}</h1>\n<p>{} {} · reference <code>{}</code> · {} sources in {} file(s) · times in s from the reference's start</p>\n",
        escape(&a.inputs.join(" ")),
        escape(&a.tool.name),
        escape(&a.tool.version),
        escape(&a.reference),
        a.sources.len(),
        a.files.len()
    );
    b.push_str("<h2>Warnings</h2>\n");
    if a.warnings.is_empty() {
        b.push_str(
            "<p class=\"ok\">No warning: every clock is constant and every triple closes.</p>\n",
        );
    }
    for w in &a.warnings {
        let _ = writeln!(
            b,
            "<p class=\"warn\">[{}] {}</p>",
            w.code,
            escape(&w.message)
        );
    }
    for o in &a.out_of_line {
        let _ = writeln!(
            b,
            "<p class=\"warn\">out of line: {}</p>",
            escape(&o.detail)
        );
    }
    b
}

/// The table of sources.
fn sources_table(a: &AuditReport, t0: f64) -> String {
    let mut b = String::new();
    b.push_str("<h2>Sources</h2>\n");
    let rows: Vec<Vec<String>> = a
        .sources
        .iter()
        .map(|s| {
            let lever = s.lever_m.map_or("–".into(), |l| {
                l.iter()
                    .map(|v| v.map_or("–".into(), |x| format!("{x:+.2}")))
                    .collect::<Vec<_>>()
                    .join(", ")
            });
            vec![
                s.name.clone(),
                s.topic.clone(),
                s.type_name.clone(),
                s.file.clone().unwrap_or_default(),
                s.rate_hz.map_or("–".into(), |r| format!("{r:.1}")),
                format!("{} ({:.1} s)", s.gaps.count, s.gaps.total_s),
                format!("{:.0}%", s.coverage.fraction_of_reference * 100.0),
                describe_clock(&s.clock, t0),
                lever,
                s.lever.as_ref().map_or(String::new(), |l| l.note.clone()),
                s.de_rmse
                    .map_or("–".into(), |d| format!("{:.2}%", d * 100.0)),
                s.ape_rmse_m.map_or("–".into(), |d| format!("{d:.3}")),
                s.domain.clone(),
            ]
        })
        .collect();
    b += &table(
        &[
            "source",
            "topic",
            "type",
            "file",
            "Hz",
            "gaps",
            "coverage",
            "clock",
            "lever x, y, z (m)",
            "lever fit",
            "DE RMSE",
            "APE RMSE (m)",
            "domain",
        ],
        &rows,
    );
    b
}

/// The offset matrix, each source's clock by domain, and the domains' table.
fn domains_section(a: &AuditReport, t0: f64) -> Result<String> {
    let mut b = String::new();
    b.push_str("<h2>Offset matrix</h2>\n");
    b += &figure(
        &render_svg(&offset_matrix(a))?,
        "Δt between every pair of sources that overlap; dark cells are the same clock",
    );
    b.push_str("<h2>Clock domains</h2>\n");
    b += &figure(
        &render_svg(&clock_lines(a, t0))?,
        "The clock model of each source against the reference",
    );
    let rows: Vec<Vec<String>> = a
        .domains
        .iter()
        .map(|d| {
            vec![
                d.name.clone(),
                d.sources.join(", "),
                if d.reference {
                    "the reference's clock".into()
                } else {
                    describe_clock(&d.clock, t0)
                },
            ]
        })
        .collect();
    b += &table(&["domain", "sources", "clock against the reference"], &rows);
    Ok(b)
}

/// The closure of every triple.
fn closure_table(a: &AuditReport) -> String {
    let mut b = String::new();
    b.push_str("<h2>Closure</h2>\n<p>Δt_AB + Δt_BC − Δt_AC of every triple, with σ from the three pairs' σ; consistent at 3σ (χ² over the pieces between clock changes).</p>\n");
    let rows: Vec<Vec<String>> = a
        .closure
        .iter()
        .map(|c| {
            vec![
                c.sources.join(", "),
                format!("{:+.2}", c.residual_s * 1e3),
                format!("{:.2}", c.sigma_s * 1e3),
                format!("{:.2}", c.chi2),
                c.dof.to_string(),
                format!("{:.3}", c.p_value),
                if c.consistent { "yes" } else { "NO" }.into(),
            ]
        })
        .collect();
    b += &table(
        &[
            "A, B, C",
            "residual (ms)",
            "σ (ms)",
            "χ²",
            "dof",
            "p",
            "consistent",
        ],
        &rows,
    );
    b
}

/// Each source's offset profile.
fn profiles(a: &AuditReport, t0: f64) -> Result<String> {
    let mut b = String::new();
    b.push_str("<h2>Offset profiles</h2>\n");
    for s in a.sources.iter().filter(|s| !s.reference) {
        let mut o = s.clock.time_offset();
        o.profile = s.clock.profile.clone();
        let fig = OffsetProfile::from_report(
            format!("{}: clock offset over the mission", s.name),
            &o,
            t0,
            (s.coverage.t_start - t0, s.coverage.t_end - t0),
        );
        b += &figure(&render_svg(&fig)?, &format!("{} ({})", s.name, s.topic));
    }
    Ok(b)
}

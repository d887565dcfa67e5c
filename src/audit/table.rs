//! The audit as text (what `trajdrift audit` prints): one line per source, the offset matrix, the
//! closure, the clock domains and the sources out of line. Names from files are escaped.

use std::fmt::Write;

use super::report::{AuditReport, Clock, ClockMethod, SourceAudit};
use crate::align::clock_model::OffsetModel;
use crate::report::escape::escape;
use crate::report::json::TimeOffsetStatus;

/// A clock in a few words, times in seconds from `t0`.
pub fn describe_clock(c: &Clock, t0: f64) -> String {
    let sigma = c
        .sigma_s
        .map_or(String::new(), |s| format!(" ± {:.1} ms", s * 1e3));
    match (c.status, c.model) {
        (TimeOffsetStatus::Weak, _) => format!("weak (best {:+.4} s)", c.offset_s),
        (TimeOffsetStatus::Given, _) if c.method == ClockMethod::Reference => "reference".into(),
        (_, OffsetModel::Constant) => match c.drift_resolution_ppm {
            Some(r) => format!(
                "constant {:+.4} s{sigma} (drift resolution {r:.0} ppm)",
                c.offset_s
            ),
            None => format!("constant {:+.4} s{sigma}", c.offset_s),
        },
        (_, OffsetModel::Linear) => format!(
            "linear {:+.4} s{sigma} at {:.0} s, {:+.1} ppm",
            c.offset_s,
            c.t_mid.map_or(f64::NAN, |t| t - t0),
            c.drift_ppm.unwrap_or(f64::NAN)
        ),
        (_, OffsetModel::Piecewise) => {
            let mut s = String::from("piecewise ");
            for (k, seg) in c.segments.iter().enumerate() {
                if k > 0 {
                    let _ = write!(s, " →[{:.0} s] ", seg.t_start - t0);
                }
                let _ = write!(s, "{:+.4}", seg.offset_s);
            }
            s.push_str(" s");
            s
        }
    }
}

fn lever(s: &SourceAudit) -> String {
    if s.reference {
        return "reference point".into();
    }
    match &s.lever_m {
        Some(l) => {
            let c = |v: Option<f64>| v.map_or("   –".into(), |x| format!("{x:+.2}"));
            let mut out = format!("{} {} {}", c(l[0]), c(l[1]), c(l[2]));
            if s.lever.as_ref().is_some_and(|f| !f.forward_separable) {
                out.push_str(" (x≈Δt)");
            }
            out
        }
        None => "–".into(),
    }
}

/// Renders the audit.
pub fn render(a: &AuditReport) -> String {
    let mut s = String::new();
    let t0 = a.sources.first().map_or(0.0, |r| r.coverage.t_start);
    let _ = writeln!(
        s,
        "audit of {} ({} sources, {} file{}); reference {}; times in s from its start",
        escape(&a.inputs.join(" ")),
        a.sources.len(),
        a.files.len(),
        if a.files.len() == 1 { "" } else { "s" },
        escape(&a.reference)
    );
    let w = a
        .sources
        .iter()
        .map(|x| x.name.chars().count())
        .max()
        .unwrap_or(6)
        .max(6);
    s += &sources_lines(a, w, t0);
    s += &matrix_lines(a, w);
    s += &closure_lines(a);
    s += &domain_lines(a, w, t0);
    if !a.out_of_line.is_empty() {
        let _ = writeln!(s, "\nout of line:");
        let mut details: Vec<&str> = Vec::new();
        for o in &a.out_of_line {
            if !details.contains(&o.detail.as_str()) {
                details.push(&o.detail);
                let _ = writeln!(s, "  {}", escape(&o.detail));
            }
        }
    }
    for w in &a.warnings {
        let _ = writeln!(s, "\nwarning [{}]: {}", w.code, escape(&w.message));
    }
    s
}

/// One line per source.
fn sources_lines(a: &AuditReport, w: usize, t0: f64) -> String {
    let mut s = String::new();
    let dw = a
        .sources
        .iter()
        .map(|x| x.domain.chars().count())
        .max()
        .unwrap_or(6)
        .max(6);
    let _ = writeln!(
        s,
        "\n{:<w$}  {:>6}  {:>4}  {:>6}  {:>7}  {:>7}  {:<dw$}  {:<20}  clock against the reference",
        "source", "Hz", "gaps", "cover", "DE", "APE m", "domain", "lever x y z (m)"
    );
    for x in &a.sources {
        let _ = writeln!(
            s,
            "{:<w$}  {:>6}  {:>4}  {:>5.0}%  {:>7}  {:>7}  {:<dw$}  {:<20}  {}",
            escape(&x.name),
            x.rate_hz.map_or("–".into(), |r| format!("{r:.1}")),
            x.gaps.count,
            x.coverage.fraction_of_reference * 100.0,
            x.de_rmse
                .map_or("–".into(), |d| format!("{:.2}%", d * 100.0)),
            x.ape_rmse_m.map_or("–".into(), |d| format!("{d:.3}")),
            escape(&x.domain),
            lever(x),
            describe_clock(&x.clock, t0)
        );
    }
    s
}

/// The offset matrix: row A, column B, Δt_AB (B's stamps onto A's clock).
fn matrix_lines(a: &AuditReport, w: usize) -> String {
    let mut s = String::new();
    let names: Vec<&str> = a.sources.iter().map(|x| x.name.as_str()).collect();
    let _ = writeln!(
        s,
        "\npairwise offsets, ms (row A, column B: B's stamps + Δt = A's clock; * not constant):"
    );
    let cw = names
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(6)
        .clamp(8, 16);
    let _ = write!(s, "{:<w$}", "");
    for n in &names {
        let short: String = n.chars().take(cw).collect();
        let _ = write!(s, "  {:>cw$}", escape(&short));
    }
    s.push('\n');
    for (i, row) in names.iter().enumerate() {
        let _ = write!(s, "{:<w$}", escape(row));
        for (j, col) in names.iter().enumerate() {
            let cell = if i == j {
                "·".to_string()
            } else {
                let (aa, bb, sign) = if i < j {
                    (row, col, 1.0)
                } else {
                    (col, row, -1.0)
                };
                a.pairs
                    .iter()
                    .find(|p| p.a == *aa && p.b == *bb)
                    .map_or("–".into(), |p| {
                        let star = if p.clock.is_constant() { "" } else { "*" };
                        if p.clock.status == TimeOffsetStatus::Weak {
                            "weak".into()
                        } else {
                            format!("{:+.1}{star}", sign * p.clock.offset_s * 1e3)
                        }
                    })
            };
            let _ = write!(s, "  {cell:>cw$}");
        }
        s.push('\n');
    }
    s
}

/// The closure: counts, the largest residual, every failing triple.
fn closure_lines(a: &AuditReport) -> String {
    let mut s = String::new();
    let failed = a.closure.iter().filter(|c| !c.consistent).count();
    let _ = writeln!(
        s,
        "\nclosure Δt_AB + Δt_BC − Δt_AC: {} triples, {} consistent (χ² at 3σ, the evaluation's σ)",
        a.closure.len(),
        a.closure.len() - failed
    );
    if let Some(worst) = a.closure.iter().max_by(|x, y| {
        (x.residual_s / x.sigma_s)
            .abs()
            .total_cmp(&(y.residual_s / y.sigma_s).abs())
    }) {
        let _ = writeln!(
            s,
            "  largest: {} {:+.1} ± {:.1} ms (p {:.3})",
            escape(&worst.sources.join(", ")),
            worst.residual_s * 1e3,
            worst.sigma_s * 1e3,
            worst.p_value
        );
    }
    for c in a.closure.iter().filter(|c| !c.consistent) {
        let _ = writeln!(
            s,
            "  fails: {} {:+.1} ± {:.1} ms (χ² {:.1}, {} dof, p {:.2e})",
            escape(&c.sources.join(", ")),
            c.residual_s * 1e3,
            c.sigma_s * 1e3,
            c.chi2,
            c.dof,
            c.p_value
        );
    }
    s
}

/// The clock domains.
fn domain_lines(a: &AuditReport, w: usize, t0: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "\nclock domains:");
    for d in &a.domains {
        let _ = writeln!(
            s,
            "  {:<w$}  {}  [{}]",
            escape(&d.name),
            if d.reference {
                "the reference's clock".to_string()
            } else {
                describe_clock(&d.clock, t0)
            },
            escape(&d.sources.join(", "))
        );
    }
    s
}

//! The short human-readable table `trajdrift eval` prints: one block per estimate with Δt, ρ, status and
//! the Drift Error per window size.

use std::fmt::Write;

use crate::report::escape::escape;
use crate::report::json::{DriftErrorReport, EstimateReport, Report, TimeOffsetReport};

fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{:.2}%", v * 100.0))
}

/// Renders `report` as text: the reference and the parameters, a block per estimate, the warnings.
pub fn render(report: &Report) -> String {
    let mut s = String::new();
    reference_lines(&mut s, report);
    for e in &report.estimates {
        estimate_lines(&mut s, e);
    }
    for w in &report.warnings {
        let _ = writeln!(s, "\nwarning [{}]: {}", w.code, w.message);
    }
    s
}

/// The reference, the parameters that shape every number below, and the reference's rows.
fn reference_lines(s: &mut String, report: &Report) {
    let p = &report.parameters;
    let _ = writeln!(
        s,
        "reference {} ({}, {} samples); ε curvature {:.2} m{}, path {:.2} m, Δt_max {} s, lever correction {}",
        escape(&report.reference.topic),
        escape(&report.reference.type_name),
        report.reference.samples,
        p.curvature_eps_m,
        p.curvature_dt_max_s
            .map_or(String::new(), |d| format!(" (Δt_max {d:.1} s)")),
        p.path_eps_m,
        p.dt_max_s,
        p.lever_correction
    );
    if let Some(rows) = report.reference.rows.describe() {
        let _ = writeln!(s, "  reference rows: {rows}");
    }
}

/// One estimate's block: what it is, its time offset, its Drift Error table, evo's metrics and the
/// intervals excluded as rotation in place.
fn estimate_lines(s: &mut String, e: &EstimateReport) {
    let _ = writeln!(
        s,
        "\nestimate {} ({}, {}, {} samples)",
        escape(&e.name),
        escape(&e.topic),
        escape(&e.type_name),
        e.samples
    );
    if let Some(rows) = e.rows.describe() {
        let _ = writeln!(s, "  rows: {rows}");
    }
    time_offset_lines(s, &e.time_offset);
    drift_error_lines(s, &e.drift_error);
    if let Some(m) = &e.standard_metrics {
        standard_lines(s, m);
    }
    if let Some(d) = e.drift_error.first() {
        if !d.excluded_intervals.is_empty() {
            let _ = writeln!(
                s,
                "  rotation in place excluded: {} intervals",
                d.excluded_intervals.len()
            );
        }
    }
}

/// The time offset found and applied, every method's result, and the clock model when one was
/// chosen.
fn time_offset_lines(s: &mut String, o: &TimeOffsetReport) {
    let _ = writeln!(
        s,
        "  time offset  {:+.4} s  applied {:+.4} s  method {}  ρ {}  confidence {}  status {}",
        o.offset_s,
        o.applied_s,
        o.method,
        o.correlation.map_or("-".into(), |c| format!("{c:.3}")),
        o.confidence.map_or("-".into(), |c| format!("{c:.2}")),
        o.status
    );
    for m in &o.methods {
        let _ = writeln!(
            s,
            "    {:<16} {}  ρ {}  confidence {}  {}",
            m.method,
            m.offset_s
                .map_or("      -".into(), |v| format!("{v:+.4} s")),
            m.correlation.map_or("-".into(), |c| format!("{c:.3}")),
            m.confidence.map_or("-".into(), |c| format!("{c:.2}")),
            m.error.as_deref().unwrap_or(m.status.as_str())
        );
    }
    if let (Some(m), Some(why)) = (o.model, o.model_reason.as_deref()) {
        let _ = writeln!(
            s,
            "  clock model  {}{} ({why})",
            m.as_str(),
            o.sigma_s
                .map_or(String::new(), |v| format!(", Δt σ {:.1} ms", v * 1e3))
        );
    }
}

/// The Drift Error table: a row per window size.
fn drift_error_lines(s: &mut String, windows: &[DriftErrorReport]) {
    let _ = writeln!(
        s,
        "  {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>10}",
        "window", "DE rmse", "median", "IQR", "windows", "dropped", "discarded"
    );
    for d in windows {
        let iqr = match (d.q1, d.q3) {
            (Some(a), Some(b)) => Some(b - a),
            _ => None,
        };
        let _ = writeln!(
            s,
            "  {:>7}m {:>8} {:>8} {:>8} {:>8} {:>8} {:>9.1}%",
            d.window_m,
            pct(d.rmse),
            pct(d.median),
            pct(iqr),
            d.windows,
            d.dropped_windows,
            d.discarded_fraction * 100.0
        );
    }
}

/// evo's APE/RPE (and KITTI drift) lines of one estimate.
fn standard_lines(s: &mut String, m: &crate::metrics::standard::in_eval::StandardMetrics) {
    for (label, r) in [
        ("APE (SE(3))", &m.ape),
        ("RPE 1 m", &m.rpe_1m),
        ("RPE 1 m point distance", &m.rpe_point_distance_1m),
    ] {
        if let Some(r) = r {
            let st = &r.stats;
            let _ = writeln!(
                s,
                "  {label:<23} rmse {:.4} m  mean {:.4}  median {:.4}  max {:.4}  pairs {}",
                st.rmse, st.mean, st.median, st.max, r.pairs
            );
        }
    }
    if let Some(k) = &m.kitti {
        let _ = writeln!(
            s,
            "  {:<23} t_err {:.3} %  r_err {:.4} deg/100 m  ({} segments)",
            "KITTI drift", k.t_err_pct, k.r_err_deg_per_100m, k.segments
        );
    }
    for n in &m.notes {
        let _ = writeln!(s, "  note: {n}");
    }
}

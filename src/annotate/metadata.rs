//! The evaluation's summary inside the annotated recording: a metadata record named `trajdrift` (a flat
//! string map any MCAP tool can show) and the full JSON report as the attachment
//! `trajdrift-report.json`.

use std::collections::BTreeMap;

use crate::report::json::Report;

/// Name of the metadata record.
pub const METADATA_NAME: &str = "trajdrift";
/// Name of the attachment holding the JSON report.
pub const ATTACHMENT_NAME: &str = "trajdrift-report.json";

/// The metadata map: tool version, every parameter (`parameters.<name>`, JSON-valued), and per estimate
/// its offset (`<name>.time_offset.*`, ρ = `correlation`) and Drift Error statistics
/// (`<name>.drift_error.<w>m.*`).
pub fn metadata_map(report: &Report) -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    m.insert("tool.name".into(), report.tool.name.clone());
    m.insert("tool.version".into(), report.tool.version.clone());
    m.insert("schema_version".into(), report.schema_version.to_string());
    m.insert("reference.topic".into(), report.reference.topic.clone());
    if let Ok(serde_json::Value::Object(params)) = serde_json::to_value(&report.parameters) {
        for (k, v) in params {
            m.insert(format!("parameters.{k}"), plain(&v));
        }
    }
    for e in &report.estimates {
        let n = &e.name;
        let o = &e.time_offset;
        m.insert(format!("{n}.topic"), e.topic.clone());
        m.insert(format!("{n}.samples"), e.samples.to_string());
        m.insert(format!("{n}.time_offset.method"), o.method.to_string());
        m.insert(format!("{n}.time_offset.offset_s"), o.offset_s.to_string());
        m.insert(
            format!("{n}.time_offset.applied_s"),
            o.applied_s.to_string(),
        );
        m.insert(format!("{n}.time_offset.status"), o.status.to_string());
        m.insert(format!("{n}.time_offset.correlation"), opt(o.correlation));
        m.insert(format!("{n}.time_offset.confidence"), opt(o.confidence));
        for d in &e.drift_error {
            let p = format!("{n}.drift_error.{}m", d.window_m);
            m.insert(format!("{p}.windows"), d.windows.to_string());
            for (k, v) in [
                ("rmse", d.rmse),
                ("mean", d.mean),
                ("median", d.median),
                ("std", d.std),
                ("q1", d.q1),
                ("q3", d.q3),
                ("p95", d.p95),
                ("min", d.min),
                ("max", d.max),
            ] {
                m.insert(format!("{p}.{k}"), opt(v));
            }
        }
    }
    m
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(|| "null".into(), |x| x.to_string())
}

/// A JSON value as text: strings without their quotes, everything else as compact JSON.
fn plain(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

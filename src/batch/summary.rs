//! Per-mission results and the summary across missions: for each estimate name (and window size), how
//! many missions, the median and IQR of the per-mission Drift Error RMSE, and each mission's Δt and
//! confidence; failed missions with their error. Written as `summary.json`, `summary.csv`,
//! `summary.md` and `summary.html` by [`super::summary_files`]. Built only from the per-mission
//! results, so `trajdrift merge` over the folders of sharded runs gives the same summary as one run.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use super::identity::Fingerprint;
use crate::report::escape::{csv_field, markdown};
use crate::report::json::Report;
use crate::stats::summarize;

/// Marks a per-mission result file.
pub const MISSION_KIND: &str = "trajdrift.mission";

/// Wall-clock figures: the only part of the results that depends on the machine and `--jobs`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    pub seconds: f64,
}

/// The result of one mission: `<mission>.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionResult {
    /// Always [`MISSION_KIND`].
    pub kind: String,
    pub mission: String,
    pub recording: String,
    /// `ok` or `failed`.
    pub status: String,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<String>,
    /// The annotated recording's file name, with `--annotate`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub annotated: Option<String>,
    /// What the result was computed from (absent in results of older versions: never reused).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub fingerprint: Option<Fingerprint>,
    pub report: Option<Report>,
    pub timing: Timing,
}

impl MissionResult {
    /// The codes of the warnings the user must see (what makes `eval` exit 3), in order, once each.
    pub fn warning_codes(&self) -> Vec<String> {
        let mut v: Vec<String> = Vec::new();
        for w in self.report.iter().flat_map(|r| &r.warnings) {
            let code = w.code.as_str().to_string();
            if !v.contains(&code) {
                v.push(code);
            }
        }
        v
    }

    /// True when some estimate's offset was weak.
    pub fn weak(&self) -> bool {
        self.report.as_ref().is_some_and(|r| {
            r.estimates
                .iter()
                .any(|e| e.time_offset.status == crate::report::json::TimeOffsetStatus::Weak)
        })
    }
}

/// One mission's numbers for one estimate and window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionEntry {
    pub mission: String,
    /// Applied offset, s.
    pub dt_s: f64,
    /// `ok`, `weak` or `given`.
    pub offset_status: crate::report::json::TimeOffsetStatus,
    pub confidence: Option<f64>,
    pub de_rmse: Option<f64>,
    /// evo's APE (SE(3), translation) RMSE on the time-aligned estimate, m (`--metrics ape`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub ape_rmse_m: Option<f64>,
    /// evo's RPE over 1 m (translation) RMSE, m (`--metrics rpe`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rpe_1m_rmse_m: Option<f64>,
}

/// One estimate name at one window size across missions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateSummary {
    pub estimate: String,
    pub window_m: f64,
    /// Missions with a DE RMSE.
    pub n: usize,
    pub de_rmse_median: Option<f64>,
    pub de_rmse_q1: Option<f64>,
    pub de_rmse_q3: Option<f64>,
    pub de_rmse_iqr: Option<f64>,
    pub missions: Vec<MissionEntry>,
}

/// A mission that failed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailedMission {
    pub mission: String,
    pub error: String,
}

/// A mission that finished with warnings the user must see (those that make `eval` exit 3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WarnedMission {
    pub mission: String,
    /// Warning codes, e.g. `truncated_recording`, `weak_time_offset`, `lever_arm_suspected`.
    pub warnings: Vec<String>,
}

/// `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub missions: usize,
    pub failed: Vec<FailedMission>,
    /// Missions with a weak offset.
    pub weak: Vec<String>,
    /// Missions that finished with a warning (a weak offset among them), with the warnings' codes.
    #[serde(default)]
    pub warned: Vec<WarnedMission>,
    /// A merge of an incomplete or inconsistent set (`merge --allow-partial`): what is wrong with it.
    #[serde(skip_serializing_if = "std::ops::Not::not", default)]
    pub partial: bool,
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub problems: Vec<String>,
    pub estimates: Vec<EstimateSummary>,
    /// Seconds per mission (machine-dependent; everything else is not).
    pub timing: BTreeMap<String, f64>,
}

impl Summary {
    /// Builds the summary; the result does not depend on the order of `results`.
    pub fn build(results: &[MissionResult]) -> Summary {
        let mut sorted: Vec<&MissionResult> = results.iter().collect();
        sorted.sort_by(|a, b| a.mission.cmp(&b.mission));
        let mut groups: BTreeMap<(String, u64), (f64, Vec<MissionEntry>)> = BTreeMap::new();
        for r in &sorted {
            let Some(report) = &r.report else { continue };
            for e in &report.estimates {
                for d in &e.drift_error {
                    groups
                        .entry((e.name.clone(), d.window_m.to_bits()))
                        .or_insert_with(|| (d.window_m, Vec::new()))
                        .1
                        .push(MissionEntry {
                            mission: r.mission.clone(),
                            dt_s: e.time_offset.applied_s,
                            offset_status: e.time_offset.status,
                            confidence: e.time_offset.confidence,
                            de_rmse: d.rmse,
                            ape_rmse_m: standard_rmse(e, |m| m.ape.as_ref()),
                            rpe_1m_rmse_m: standard_rmse(e, |m| m.rpe_1m.as_ref()),
                        });
                }
            }
        }
        let mut estimates: Vec<EstimateSummary> = groups
            .into_iter()
            .map(|((name, _), (window_m, missions))| {
                let rmse: Vec<f64> = missions.iter().filter_map(|m| m.de_rmse).collect();
                let s = summarize(&rmse);
                EstimateSummary {
                    estimate: name,
                    window_m,
                    n: s.map_or(0, |s| s.n),
                    de_rmse_median: s.map(|s| s.median),
                    de_rmse_q1: s.map(|s| s.q1),
                    de_rmse_q3: s.map(|s| s.q3),
                    de_rmse_iqr: s.map(|s| s.q3 - s.q1),
                    missions,
                }
            })
            .collect();
        estimates.sort_by(|a, b| {
            a.estimate
                .cmp(&b.estimate)
                .then(a.window_m.total_cmp(&b.window_m))
        });
        Summary {
            missions: sorted.len(),
            failed: sorted
                .iter()
                .filter(|r| r.status != "ok")
                .map(|r| FailedMission {
                    mission: r.mission.clone(),
                    error: r.error.clone().unwrap_or_default(),
                })
                .collect(),
            weak: sorted
                .iter()
                .filter(|r| r.weak())
                .map(|r| r.mission.clone())
                .collect(),
            warned: sorted
                .iter()
                .filter_map(|r| {
                    let codes = r.warning_codes();
                    (!codes.is_empty()).then(|| WarnedMission {
                        mission: r.mission.clone(),
                        warnings: codes,
                    })
                })
                .collect(),
            partial: false,
            problems: Vec::new(),
            estimates,
            timing: sorted
                .iter()
                .map(|r| (r.mission.clone(), r.timing.seconds))
                .collect(),
        }
    }

    /// The batch's exit code, as `eval`'s: 1 when a mission failed, else 3 when a mission finished
    /// with a warning (or the summary is partial), else 0.
    pub fn exit_code(&self) -> u8 {
        if !self.failed.is_empty() {
            1
        } else if !self.warned.is_empty() || !self.weak.is_empty() || self.partial {
            3
        } else {
            0
        }
    }

    /// One CSV row per mission, estimate and window; failed missions with their error. Text cells
    /// through the CSV sink ([`csv_field`]: no formula, one line).
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "mission,estimate,window_m,status,dt_s,offset_status,confidence,de_rmse,error,ape_rmse_m,rpe_1m_rmse_m,warnings\n",
        );
        let opt = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
        let warnings = |mission: &str| {
            self.warned
                .iter()
                .find(|w| w.mission == mission)
                .map_or(String::new(), |w| csv_field(&w.warnings.join(" ")))
        };
        let mut rows: Vec<(String, String)> = Vec::new();
        for e in &self.estimates {
            for m in &e.missions {
                rows.push((
                    m.mission.clone(),
                    format!(
                        "{},{},{},ok,{},{},{},{},,{},{},{}\n",
                        csv_field(&m.mission),
                        csv_field(&e.estimate),
                        e.window_m,
                        m.dt_s,
                        csv_field(&m.offset_status.to_string()),
                        opt(m.confidence),
                        opt(m.de_rmse),
                        opt(m.ape_rmse_m),
                        opt(m.rpe_1m_rmse_m),
                        warnings(&m.mission)
                    ),
                ));
            }
        }
        for f in &self.failed {
            rows.push((
                f.mission.clone(),
                format!(
                    "{},,,failed,,,,,{},,,\n",
                    csv_field(&f.mission),
                    csv_field(&f.error)
                ),
            ));
        }
        rows.sort_by(|a, b| a.0.cmp(&b.0));
        for (_, r) in rows {
            s.push_str(&r);
        }
        s
    }

    /// A Markdown page: one table per estimate and window, then the warnings and the failures; every
    /// name and message through the Markdown sink ([`markdown`]).
    pub fn to_markdown(&self) -> String {
        let mut s = String::from("# trajdrift batch summary\n\n");
        let pct = |v: Option<f64>| v.map_or("–".into(), |x| format!("{:.2} %", 100.0 * x));
        let metres = |v: Option<f64>| v.map_or("–".into(), |x| format!("{x:.4}"));
        if self.partial {
            s.push_str(
                "**Partial**: merged from an incomplete or inconsistent set of results:\n\n",
            );
            for p in &self.problems {
                let _ = writeln!(s, "- {}", markdown(p));
            }
            s.push('\n');
        }
        let _ = writeln!(
            s,
            "{} missions, {} failed, {} with a warning ({} with a weak offset).\n",
            self.missions,
            self.failed.len(),
            self.warned.len(),
            self.weak.len()
        );
        for e in &self.estimates {
            let _ = writeln!(
                s,
                "## {} — {} m windows\n\nn = {}, DE RMSE median {}, IQR {} ({} – {})\n",
                markdown(&e.estimate),
                e.window_m,
                e.n,
                pct(e.de_rmse_median),
                pct(e.de_rmse_iqr),
                pct(e.de_rmse_q1),
                pct(e.de_rmse_q3)
            );
            s.push_str(
                "| mission | Δt (s) | offset | confidence | DE RMSE | APE RMSE (m) | RPE 1 m RMSE (m) |\n|---|---:|---|---:|---:|---:|---:|\n",
            );
            for m in &e.missions {
                let _ = writeln!(
                    s,
                    "| {} | {:+.4} | {} | {} | {} | {} | {} |",
                    markdown(&m.mission),
                    m.dt_s,
                    markdown(&m.offset_status.to_string()),
                    m.confidence.map_or("–".into(), |c| format!("{c:.2}")),
                    pct(m.de_rmse),
                    metres(m.ape_rmse_m),
                    metres(m.rpe_1m_rmse_m)
                );
            }
            s.push('\n');
        }
        if !self.warned.is_empty() {
            s.push_str("## Missions with a warning\n\n| mission | warnings |\n|---|---|\n");
            for w in &self.warned {
                let _ = writeln!(
                    s,
                    "| {} | {} |",
                    markdown(&w.mission),
                    markdown(&w.warnings.join(", "))
                );
            }
            s.push('\n');
        }
        if !self.failed.is_empty() {
            s.push_str("## Failed missions\n\n| mission | error |\n|---|---|\n");
            for f in &self.failed {
                let _ = writeln!(s, "| {} | {} |", markdown(&f.mission), markdown(&f.error));
            }
        }
        s
    }
}

/// The RMSE of one standard metric of an estimate, when computed.
fn standard_rmse(
    e: &crate::report::json::EstimateReport,
    pick: impl Fn(
        &crate::metrics::standard::in_eval::StandardMetrics,
    ) -> Option<&crate::metrics::standard::MetricResult>,
) -> Option<f64> {
    e.standard_metrics
        .as_ref()
        .and_then(pick)
        .map(|r| r.stats.rmse)
}

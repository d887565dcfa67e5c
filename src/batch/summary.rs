//! Per-mission results and the summary across missions: for each estimate name (and window size), how
//! many missions, the median and IQR of the per-mission Drift Error RMSE, and each mission's Δt and
//! confidence; failed missions with their error. Written as `summary.json`, `summary.csv` and
//! `summary.md`. Built only from the per-mission results, so `trajdrift merge` over the folders of
//! sharded runs gives the same summary as one run.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::output::write_output;
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
    pub report: Option<Report>,
    pub timing: Timing,
}

impl MissionResult {
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

/// `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub missions: usize,
    pub failed: Vec<FailedMission>,
    /// Missions with a weak offset.
    pub weak: Vec<String>,
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
            estimates,
            timing: sorted
                .iter()
                .map(|r| (r.mission.clone(), r.timing.seconds))
                .collect(),
        }
    }

    /// The batch's exit code: 1 when a mission failed, else 3 when an offset was weak, else 0.
    pub fn exit_code(&self) -> u8 {
        if !self.failed.is_empty() {
            1
        } else if !self.weak.is_empty() {
            3
        } else {
            0
        }
    }

    /// One CSV row per mission, estimate and window; failed missions with their error.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "mission,estimate,window_m,status,dt_s,offset_status,confidence,de_rmse,error,ape_rmse_m,rpe_1m_rmse_m\n",
        );
        let opt = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
        let mut rows: Vec<(String, String)> = Vec::new();
        for e in &self.estimates {
            for m in &e.missions {
                rows.push((
                    m.mission.clone(),
                    format!(
                        "{},{},{},ok,{},{},{},{},,{},{}\n",
                        csv(&m.mission),
                        csv(&e.estimate),
                        e.window_m,
                        m.dt_s,
                        m.offset_status,
                        opt(m.confidence),
                        opt(m.de_rmse),
                        opt(m.ape_rmse_m),
                        opt(m.rpe_1m_rmse_m)
                    ),
                ));
            }
        }
        for f in &self.failed {
            rows.push((
                f.mission.clone(),
                format!("{},,,failed,,,,,{},,\n", csv(&f.mission), csv(&f.error)),
            ));
        }
        rows.sort_by(|a, b| a.0.cmp(&b.0));
        for (_, r) in rows {
            s.push_str(&r);
        }
        s
    }

    /// A Markdown page: one table per estimate and window, then the failures.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from("# trajdrift batch summary\n\n");
        let pct = |v: Option<f64>| v.map_or("–".into(), |x| format!("{:.2} %", 100.0 * x));
        let metres = |v: Option<f64>| v.map_or("–".into(), |x| format!("{x:.4}"));
        let _ = writeln!(
            s,
            "{} missions, {} failed, {} with a weak offset.\n",
            self.missions,
            self.failed.len(),
            self.weak.len()
        );
        for e in &self.estimates {
            let _ = writeln!(
                s,
                "## {} — {} m windows\n\nn = {}, DE RMSE median {}, IQR {} ({} – {})\n",
                e.estimate,
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
                    m.mission,
                    m.dt_s,
                    m.offset_status,
                    m.confidence.map_or("–".into(), |c| format!("{c:.2}")),
                    pct(m.de_rmse),
                    metres(m.ape_rmse_m),
                    metres(m.rpe_1m_rmse_m)
                );
            }
            s.push('\n');
        }
        if !self.failed.is_empty() {
            s.push_str("## Failed missions\n\n| mission | error |\n|---|---|\n");
            for f in &self.failed {
                let _ = writeln!(s, "| {} | {} |", f.mission, f.error.replace('|', "\\|"));
            }
        }
        s
    }

    /// Writes `summary.json`, `summary.csv` and `summary.md` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        self.write_as(dir, "summary")
    }

    /// Writes `STEM.json`, `STEM.csv` and `STEM.md` into `dir` (a shard writes its own stem).
    pub fn write_as(&self, dir: &Path, stem: &str) -> Result<()> {
        let path = |ext: &str| dir.join(format!("{stem}.{ext}"));
        let mut json = serde_json::to_vec_pretty(self).map_err(|e| Error::Output {
            path: path("json"),
            detail: e.to_string(),
        })?;
        json.push(b'\n');
        write_output(&path("json"), &json)?;
        write_output(&path("csv"), self.to_csv().as_bytes())?;
        write_output(&path("md"), self.to_markdown().as_bytes())?;
        let html = super::summary_html::render(self, dir);
        write_output(&path("html"), html.as_bytes())
    }
}

fn csv(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\"").replace('\n', " "))
    } else {
        s.to_string()
    }
}

/// Reads every per-mission result (`*.json` with `kind` = [`MISSION_KIND`]) in `dirs`; a mission found
/// twice is an error.
pub fn read_results(dirs: &[PathBuf]) -> Result<Vec<MissionResult>> {
    let mut out: Vec<MissionResult> = Vec::new();
    for dir in dirs {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| Error::io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .collect();
        paths.sort();
        for p in paths {
            let Ok(text) = std::fs::read(&p) else {
                continue;
            };
            let Ok(value) = serde_json::from_slice::<serde_json::Value>(&text) else {
                continue;
            };
            if value.get("kind").and_then(|k| k.as_str()) != Some(MISSION_KIND) {
                continue;
            }
            let r: MissionResult = serde_json::from_value(value).map_err(|e| {
                Error::InvalidArgument(format!("{}: not a mission result: {e}", p.display()))
            })?;
            if out.iter().any(|x| x.mission == r.mission) {
                return Err(Error::InvalidArgument(format!(
                    "{}: mission `{}` appears twice in the folders merged",
                    p.display(),
                    r.mission
                )));
            }
            out.push(r);
        }
    }
    if out.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "no mission result (*.json from `trajdrift batch`) in {}",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(out)
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

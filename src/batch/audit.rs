//! `trajdrift batch --audit`: every mission of a dataset audited ([`crate::audit`]), in parallel, and
//! the page a curator opens first: per mission its clock domains and any source out of line.
//!
//! Each mission writes `<mission>.audit.json` (the audit, or its failure) and, with `--html`,
//! `<mission>.audit.html`; the batch writes `audit-summary.json` and `audit-summary.md`. In a folder
//! every recording is a mission and so is every subfolder of recordings (an audit needs a mission's
//! files together: GrandTour's bags, a folder of per-source MCAPs). Missions fail alone; the summary
//! is built in name order, so it does not depend on `--jobs`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::manifest::Manifest;
use super::run::{BatchEvent, BatchProgress};
use crate::audit::discover::SourceRequest;
use crate::audit::report::{AuditReport, OutOfLine};
use crate::audit::{audit, AuditConfig};
use crate::diag::WarningCode;
use crate::error::{Error, Result};
use crate::eval::config::TrajectoryInput;
use crate::eval::parameters::Parameters;
use crate::output::{write_json, write_output, OutputGuard};

/// Marks a per-mission audit result.
pub const MISSION_AUDIT_KIND: &str = "trajdrift.mission-audit";

/// One mission to audit.
#[derive(Debug, Clone)]
pub struct AuditMission {
    pub name: String,
    pub recordings: Vec<PathBuf>,
    pub request: SourceRequest,
    pub params: Parameters,
}

/// The missions of a folder: each recording, and each subfolder of recordings as one mission.
pub fn missions_in(
    dir: &Path,
    request: &SourceRequest,
    params: &Parameters,
) -> Result<Vec<AuditMission>> {
    let mut out = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            !p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .collect();
    entries.sort();
    for p in entries {
        let is_mission = crate::sources::open::is_recording_entry(&p)
            || (p.is_dir() && crate::sources::open::recordings_in(&p).is_ok());
        if !is_mission {
            continue;
        }
        let stem = if p.is_file() {
            p.file_stem().map(|s| s.to_string_lossy().into_owned())
        } else {
            p.file_name().map(|s| s.to_string_lossy().into_owned())
        }
        .unwrap_or_default();
        let name: String = stem
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        out.push(AuditMission {
            name,
            recordings: vec![p],
            request: request.clone(),
            params: params.clone(),
        });
    }
    if out.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "{}: no mission (recordings .mcap, .bag, rosbag2 folders, or folders of them)",
            dir.display()
        )));
    }
    Ok(out)
}

/// The missions of a manifest: its reference, and its estimates as the sources (all readable topics
/// when it lists none).
pub fn from_manifest(m: &Manifest) -> Vec<AuditMission> {
    m.missions
        .iter()
        .map(|spec| {
            let topic = |i: &crate::eval::config::NamedInput| match &i.input {
                TrajectoryInput::Topic(t) => Some(format!("{}={t}", i.name)),
                TrajectoryInput::TumFile(_) => None,
            };
            let reference = match &spec.config.reference.input {
                TrajectoryInput::Topic(t) => Some(t.clone()),
                TrajectoryInput::TumFile(_) => None,
            };
            AuditMission {
                name: spec.name.clone(),
                recordings: spec.config.recordings(),
                request: SourceRequest {
                    reference,
                    sources: spec.config.estimates.iter().filter_map(topic).collect(),
                    preset: None,
                },
                params: spec.config.params.clone(),
            }
        })
        .collect()
}

/// A domain as the summary shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DomainLine {
    pub name: String,
    pub sources: Vec<String>,
    pub reference: bool,
    /// The domain's clock against the reference, in words.
    pub clock: String,
}

/// Whether a mission was audited.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MissionStatus {
    Ok,
    Failed,
}

/// One mission's line of the summary (and the head of `<mission>.audit.json` when it failed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionAudit {
    /// Always [`MISSION_AUDIT_KIND`].
    pub kind: String,
    pub mission: String,
    pub recordings: Vec<String>,
    pub status: MissionStatus,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<String>,
    pub reference: Option<String>,
    pub sources: usize,
    pub domains: Vec<DomainLine>,
    pub out_of_line: Vec<OutOfLine>,
    /// Warning codes, one per warning.
    pub warnings: Vec<WarningCode>,
    pub seconds: f64,
}

/// `audit-summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AuditSummary {
    pub missions: Vec<MissionAudit>,
}

impl AuditSummary {
    /// 1 when a mission failed, else 3 when a mission warned, else 0.
    pub fn exit_code(&self) -> u8 {
        if self.missions.iter().any(|m| m.status != MissionStatus::Ok) {
            1
        } else if self.missions.iter().any(|m| !m.warnings.is_empty()) {
            3
        } else {
            0
        }
    }

    /// The Markdown page: an overview row per mission, then each mission's domains.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from("# trajdrift audit summary\n\n");
        s.push_str("| mission | sources | clock domains | out of line | warnings |\n|---|---:|---:|---|---|\n");
        let cell = |t: &str| t.replace('|', "\\|");
        for m in &self.missions {
            if m.status != MissionStatus::Ok {
                let _ = writeln!(
                    s,
                    "| {} | – | – | failed: {} | |",
                    cell(&m.mission),
                    cell(m.error.as_deref().unwrap_or(""))
                );
                continue;
            }
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} |",
                cell(&m.mission),
                m.sources,
                m.domains.len(),
                cell(
                    &m.out_of_line
                        .iter()
                        .map(|o| o.source.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                cell(
                    &m.warnings
                        .iter()
                        .map(|w| w.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            );
        }
        for m in self
            .missions
            .iter()
            .filter(|m| m.status == MissionStatus::Ok)
        {
            let _ = writeln!(
                s,
                "\n## {}\n\nreference {}\n\n| clock domain | sources | clock against the reference |\n|---|---|---|",
                cell(&m.mission),
                cell(m.reference.as_deref().unwrap_or(""))
            );
            for d in &m.domains {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} |",
                    cell(&d.name),
                    cell(&d.sources.join(", ")),
                    cell(&d.clock)
                );
            }
            if !m.out_of_line.is_empty() {
                s.push_str("\nOut of line:\n\n");
                for o in &m.out_of_line {
                    let _ = writeln!(s, "- {}", o.detail);
                }
            }
        }
        s
    }

    /// Writes `audit-summary.json` and `audit-summary.md` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        write_json(&dir.join("audit-summary.json"), self)?;
        write_output(&dir.join("audit-summary.md"), self.to_markdown().as_bytes())
    }
}

fn line_of(name: &str, recordings: &[PathBuf], a: &AuditReport, seconds: f64) -> MissionAudit {
    let t0 = a.sources.first().map_or(0.0, |r| r.coverage.t_start);
    MissionAudit {
        kind: MISSION_AUDIT_KIND.into(),
        mission: name.into(),
        recordings: recordings.iter().map(|p| p.display().to_string()).collect(),
        status: MissionStatus::Ok,
        error: None,
        reference: Some(a.reference.clone()),
        sources: a.sources.len(),
        domains: a
            .domains
            .iter()
            .map(|d| DomainLine {
                name: d.name.clone(),
                sources: d.sources.clone(),
                reference: d.reference,
                clock: if d.reference {
                    "the reference's clock".into()
                } else {
                    crate::audit::table::describe_clock(&d.clock, t0)
                },
            })
            .collect(),
        out_of_line: a.out_of_line.clone(),
        warnings: a.warnings.iter().map(|w| w.code).collect(),
        seconds,
    }
}

/// Audits every mission into `out_dir` (`jobs` at once, 0 = the cores); `html` also writes each
/// mission's page.
pub fn run_audit_batch(
    missions: &[AuditMission],
    out_dir: &Path,
    jobs: usize,
    html: bool,
    progress: BatchProgress<'_>,
) -> Result<AuditSummary> {
    claim_outputs(missions, out_dir, html)?;
    progress(BatchEvent::Planned {
        missions: missions.len(),
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::InvalidArgument(format!("--jobs {jobs}: {e}")))?;
    let lines: Vec<Result<MissionAudit>> = pool.install(|| {
        missions
            .par_iter()
            .map(|m| audit_mission(m, out_dir, html, progress))
            .collect()
    });
    let mut missions_out = lines.into_iter().collect::<Result<Vec<_>>>()?;
    missions_out.sort_by(|a, b| a.mission.cmp(&b.mission));
    let summary = AuditSummary {
        missions: missions_out,
    };
    summary.write(out_dir)?;
    Ok(summary)
}

/// Every output claimed before any work: the summary, each mission's audit and page.
fn claim_outputs(missions: &[AuditMission], out_dir: &Path, html: bool) -> Result<()> {
    let mut guard = OutputGuard::new(missions.iter().flat_map(|m| m.recordings.clone()));
    guard.claim_dir("--out", out_dir)?;
    std::fs::create_dir_all(out_dir).map_err(|e| Error::Output {
        path: out_dir.to_path_buf(),
        detail: e.to_string(),
    })?;
    for name in ["audit-summary.json", "audit-summary.md"] {
        guard.claim("--out", &out_dir.join(name))?;
    }
    for m in missions {
        guard.claim("--out", &out_dir.join(format!("{}.audit.json", m.name)))?;
        if html {
            guard.claim("--html", &out_dir.join(format!("{}.audit.html", m.name)))?;
        }
    }
    Ok(())
}

/// Audits one mission and writes its audit (and page): its line of the summary, `failed` with the
/// error when the audit failed.
fn audit_mission(
    m: &AuditMission,
    out_dir: &Path,
    html: bool,
    progress: BatchProgress<'_>,
) -> Result<MissionAudit> {
    let start = Instant::now();
    let bytes = m
        .recordings
        .iter()
        .map(|p| crate::sources::open::input_size(p))
        .sum();
    progress(BatchEvent::Started {
        mission: &m.name,
        bytes,
    });
    let config = AuditConfig {
        recordings: m.recordings.clone(),
        request: m.request.clone(),
        params: m.params.clone(),
    };
    let outcome = audit(&config, &|b| {
        progress(BatchEvent::Read {
            mission: &m.name,
            bytes: b,
        })
    });
    progress(BatchEvent::Finished {
        mission: &m.name,
        ok: outcome.is_ok(),
    });
    let seconds = start.elapsed().as_secs_f64();
    let path = out_dir.join(format!("{}.audit.json", m.name));
    match outcome {
        Ok(o) => {
            write_json(&path, &o.report)?;
            if html {
                let page = crate::audit::html::render(&o.report)?;
                write_output(
                    &out_dir.join(format!("{}.audit.html", m.name)),
                    page.as_bytes(),
                )?;
            }
            Ok(line_of(&m.name, &m.recordings, &o.report, seconds))
        }
        Err(e) => {
            let line = MissionAudit {
                kind: MISSION_AUDIT_KIND.into(),
                mission: m.name.clone(),
                recordings: m
                    .recordings
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect(),
                status: MissionStatus::Failed,
                error: Some(e.to_string()),
                reference: None,
                sources: 0,
                domains: Vec::new(),
                out_of_line: Vec::new(),
                warnings: Vec::new(),
                seconds,
            };
            write_json(&path, &line)?;
            Ok(line)
        }
    }
}

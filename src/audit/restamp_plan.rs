//! Which messages `restamp` moves, and by which clock.
//!
//! A restamp domain is a set of messages recorded on one clock. By default it is **the file a source
//! came from** when the mission is several files (GrandTour records one bag per sensor group or
//! computer: every message of that bag is on its clock, point clouds and IMU included), or **the
//! source's topic alone** in a single recording. `--domain NAME=TOPIC,…` widens one to topics the
//! audit did not evaluate (all topics a computer recorded); its topics leave their default domain.
//!
//! Each domain moves by the clock of the audit's clock domain its sources belong to
//! ([`super::report::Domain::clock`]: its most precise member's model against the reference). A
//! domain whose sources sit on different clocks is refused, naming them; one on the reference's clock
//! is left as it is (moving it by its measured Δt would add the measurement's error to good stamps);
//! a source without a confident clock is left as it is, and said. A file holding sources of two
//! clocks falls back to one domain per topic, and says so.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::report::{AuditReport, Clock};
use crate::clock::ClockCorrection;
use crate::error::{Error, Result};
use crate::report::json::TimeOffsetStatus;

/// What a domain covers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Scope {
    /// Every message of this file of the mission.
    File(PathBuf),
    /// Every message on these topics (in any file).
    Topics(Vec<String>),
}

/// One domain to move.
#[derive(Debug, Clone)]
pub struct RestampDomain {
    pub name: String,
    pub scope: Scope,
    /// The audited sources in it.
    pub sources: Vec<String>,
    /// The audit domain whose clock it takes.
    pub audit_domain: String,
    pub clock: Clock,
    pub correction: ClockCorrection,
}

/// Every domain to move, and what was left alone.
#[derive(Debug, Clone)]
pub struct RestampPlan {
    pub domains: Vec<RestampDomain>,
    /// One line per choice the user should know (sources left unchanged, files split by topic).
    pub notes: Vec<String>,
}

impl RestampPlan {
    /// The domain a message belongs to: a topic domain first, then its file's.
    pub fn domain_of(&self, file: Option<&Path>, topic: &str) -> Option<usize> {
        self.domains
            .iter()
            .position(|d| matches!(&d.scope, Scope::Topics(t) if t.iter().any(|x| x == topic)))
            .or_else(|| {
                let file = file?;
                self.domains
                    .iter()
                    .position(|d| matches!(&d.scope, Scope::File(f) if same_file(f, file)))
            })
    }
}

/// The same file, however its path is written (as the audit named it, as the restamp opened it).
fn same_file(a: &Path, b: &Path) -> bool {
    a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// Parses `--domain NAME=TOPIC[,TOPIC…]`.
pub fn parse_domain(spec: &str) -> Result<(String, Vec<String>)> {
    let bad = || {
        Error::InvalidArgument(format!(
            "--domain takes NAME=TOPIC[,TOPIC...], e.g. nuc=/lio/odom,/lio/points,/imu; got `{spec}`"
        ))
    };
    let (name, topics) = spec.split_once('=').ok_or_else(bad)?;
    let topics: Vec<String> = topics
        .split(',')
        .map(|t| t.trim().to_string())
        .filter(|t| !t.is_empty())
        .collect();
    if name.trim().is_empty() || topics.is_empty() {
        return Err(bad());
    }
    Ok((name.trim().to_string(), topics))
}

/// The topic a source's messages are on (a TF chain's: `/tf`).
fn message_topic(topic: &str) -> &str {
    if topic.starts_with("/tf:") {
        "/tf"
    } else {
        topic
    }
}

/// Plans the restamp of a mission of `files` (one entry: a single recording) by `audit`, with the
/// user's `--domain` specs.
pub fn plan(
    audit: &AuditReport,
    files: &[PathBuf],
    domains: &[(String, Vec<String>)],
) -> Result<RestampPlan> {
    let mut notes = Vec::new();
    let audit_domain = |source: &str| -> Option<&super::report::Domain> {
        audit
            .domains
            .iter()
            .find(|d| d.sources.iter().any(|s| s == source))
    };
    // The sources that can move: not the reference's domain, with a confident clock.
    let mut movable: Vec<&super::report::SourceAudit> = Vec::new();
    for s in audit.sources.iter().filter(|s| !s.reference) {
        let Some(d) = audit_domain(&s.name) else {
            continue;
        };
        if d.reference {
            continue;
        }
        if s.clock.status != TimeOffsetStatus::Ok {
            notes.push(format!(
                "{}: no confident clock against the reference; left unchanged",
                s.name
            ));
            continue;
        }
        movable.push(s);
    }
    let mut out: Vec<RestampDomain> = Vec::new();
    let mut claimed_topics: Vec<String> = Vec::new();
    // --domain first.
    for (name, topics) in domains {
        let members: Vec<&super::report::SourceAudit> = audit
            .sources
            .iter()
            .filter(|s| {
                topics
                    .iter()
                    .any(|t| t == message_topic(&s.topic) || *t == s.topic)
            })
            .collect();
        if members.is_empty() {
            return Err(Error::InvalidArgument(format!(
                "--domain {name}: none of its topics ({}) is a source of the audit, so its clock is unknown; add one the audit evaluated",
                topics.join(", ")
            )));
        }
        let mut homes: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for m in &members {
            if let Some(d) = audit_domain(&m.name) {
                homes
                    .entry(d.name.clone())
                    .or_default()
                    .push(m.name.clone());
            }
        }
        if homes.len() > 1 {
            return Err(Error::InvalidArgument(format!(
                "--domain {name}: its sources are on different clocks ({}); split it",
                homes
                    .iter()
                    .map(|(d, s)| format!("{} in clock domain {d}", s.join(", ")))
                    .collect::<Vec<_>>()
                    .join("; ")
            )));
        }
        claimed_topics.extend(topics.iter().cloned());
        let Some((home, _)) = homes.into_iter().next() else {
            continue;
        };
        let Some(d) = audit.domains.iter().find(|d| d.name == home) else {
            continue;
        };
        if d.reference {
            notes.push(format!(
                "--domain {name}: on the reference's clock; left unchanged"
            ));
            continue;
        }
        out.push(RestampDomain {
            name: name.clone(),
            scope: Scope::Topics(topics.clone()),
            sources: members.iter().map(|m| m.name.clone()).collect(),
            audit_domain: d.name.clone(),
            clock: d.clock.clone(),
            correction: d.clock.correction(),
        });
    }
    // Defaults: the file of each source (several files), else its topic.
    let mut by_file: BTreeMap<PathBuf, Vec<&super::report::SourceAudit>> = BTreeMap::new();
    let mut alone: Vec<&super::report::SourceAudit> = Vec::new();
    for s in movable {
        if claimed_topics
            .iter()
            .any(|t| t == &s.topic || t == message_topic(&s.topic))
        {
            continue;
        }
        match (&s.file, files.len() > 1) {
            (Some(f), true) => by_file.entry(PathBuf::from(f)).or_default().push(s),
            _ => alone.push(s),
        }
    }
    for (file, members) in by_file {
        // Every audited source in the file must be on one clock (the reference's sources too).
        let in_file: Vec<&super::report::SourceAudit> = audit
            .sources
            .iter()
            .filter(|s| s.file.as_deref() == Some(&*file.to_string_lossy()))
            .collect();
        let mut homes: Vec<&str> = in_file
            .iter()
            .filter_map(|s| audit_domain(&s.name).map(|d| d.name.as_str()))
            .collect();
        homes.sort_unstable();
        homes.dedup();
        if homes.len() == 1 {
            let Some(d) = audit_domain(&members[0].name) else {
                continue;
            };
            out.push(RestampDomain {
                name: file.file_name().map_or_else(
                    || file.display().to_string(),
                    |n| n.to_string_lossy().into_owned(),
                ),
                scope: Scope::File(file.clone()),
                sources: members.iter().map(|m| m.name.clone()).collect(),
                audit_domain: d.name.clone(),
                clock: d.clock.clone(),
                correction: d.clock.correction(),
            });
        } else {
            notes.push(format!(
                "{}: holds sources of {} clocks ({}); each source's topic is moved alone (give --domain to move more of the file)",
                file.display(),
                homes.len(),
                homes.join(", ")
            ));
            alone.extend(members);
        }
    }
    for s in alone {
        let Some(d) = audit_domain(&s.name) else {
            continue;
        };
        out.push(RestampDomain {
            name: s.name.clone(),
            scope: Scope::Topics(vec![message_topic(&s.topic).to_string()]),
            sources: vec![s.name.clone()],
            audit_domain: d.name.clone(),
            clock: d.clock.clone(),
            correction: d.clock.correction(),
        });
    }
    Ok(RestampPlan {
        domains: out,
        notes,
    })
}

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

type SourceRef<'a> = &'a super::report::SourceAudit;

/// The audit's domain holding `source`.
fn domain_of<'a>(audit: &'a AuditReport, source: &str) -> Option<&'a super::report::Domain> {
    audit
        .domains
        .iter()
        .find(|d| d.sources.iter().any(|s| s == source))
}

/// A planned domain moved by the audit's domain `d`.
fn moved_by(
    name: String,
    scope: Scope,
    sources: Vec<String>,
    d: &super::report::Domain,
) -> RestampDomain {
    RestampDomain {
        name,
        scope,
        sources,
        audit_domain: d.name.clone(),
        clock: d.clock.clone(),
        correction: d.clock.correction(),
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
    let movable = movable_sources(audit, &mut notes);
    let mut out: Vec<RestampDomain> = Vec::new();
    let mut claimed_topics: Vec<String> = Vec::new();
    // --domain first.
    for (name, topics) in domains {
        claimed_topics.extend(topics.iter().cloned());
        out.extend(user_domain(audit, name, topics, &mut notes)?);
    }
    // Defaults: the file of each source (several files), else its topic.
    let mut by_file: BTreeMap<PathBuf, Vec<SourceRef<'_>>> = BTreeMap::new();
    let mut alone: Vec<SourceRef<'_>> = Vec::new();
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
        match file_domain(audit, &file, &members, &mut notes) {
            Some(d) => out.push(d),
            None => alone.extend(members),
        }
    }
    for s in alone {
        let Some(d) = domain_of(audit, &s.name) else {
            continue;
        };
        let scope = Scope::Topics(vec![message_topic(&s.topic).to_string()]);
        out.push(moved_by(s.name.clone(), scope, vec![s.name.clone()], d));
    }
    Ok(RestampPlan {
        domains: out,
        notes,
    })
}

/// The topics of `audit`'s sources that `files` do not hold: an audit of another recording when there
/// are any (restamping by it would move nothing, or the wrong messages).
pub fn missing_topics(audit: &AuditReport, files: &[PathBuf]) -> Result<Vec<String>> {
    let held = super::discover::topic_files(files)?;
    let mut missing: Vec<String> = Vec::new();
    for s in &audit.sources {
        let topic = message_topic(&s.topic);
        if !held.contains_key(topic) && !missing.iter().any(|m| m == topic) {
            missing.push(topic.to_string());
        }
    }
    Ok(missing)
}

/// The sources that can move: not in the reference's domain, with a confident clock.
fn movable_sources<'a>(audit: &'a AuditReport, notes: &mut Vec<String>) -> Vec<SourceRef<'a>> {
    let mut movable = Vec::new();
    for s in audit.sources.iter().filter(|s| !s.reference) {
        let Some(d) = domain_of(audit, &s.name) else {
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
    movable
}

/// A `--domain NAME=TOPIC,…`: moved by the clock of the audited sources among its topics, which must
/// share one; `None` when that clock is the reference's.
fn user_domain(
    audit: &AuditReport,
    name: &str,
    topics: &[String],
    notes: &mut Vec<String>,
) -> Result<Option<RestampDomain>> {
    let members: Vec<SourceRef<'_>> = audit
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
        if let Some(d) = domain_of(audit, &m.name) {
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
    let Some((home, _)) = homes.into_iter().next() else {
        return Ok(None);
    };
    let Some(d) = audit.domains.iter().find(|d| d.name == home) else {
        return Ok(None);
    };
    if d.reference {
        notes.push(format!(
            "--domain {name}: on the reference's clock; left unchanged"
        ));
        return Ok(None);
    }
    let sources = members.iter().map(|m| m.name.clone()).collect();
    Ok(Some(moved_by(
        name.to_string(),
        Scope::Topics(topics.to_vec()),
        sources,
        d,
    )))
}

/// A file of the mission moved as one domain, when every audited source in it (the reference's
/// too) is on one clock; `None` (with a note) when not: its sources then move alone.
fn file_domain(
    audit: &AuditReport,
    file: &Path,
    members: &[SourceRef<'_>],
    notes: &mut Vec<String>,
) -> Option<RestampDomain> {
    let mut homes: Vec<&str> = audit
        .sources
        .iter()
        .filter(|s| s.file.as_deref() == Some(&*file.to_string_lossy()))
        .filter_map(|s| domain_of(audit, &s.name).map(|d| d.name.as_str()))
        .collect();
    homes.sort_unstable();
    homes.dedup();
    if homes.len() != 1 {
        notes.push(format!(
            "{}: holds sources of {} clocks ({}); each source's topic is moved alone (give --domain to move more of the file)",
            file.display(),
            homes.len(),
            homes.join(", ")
        ));
        return None;
    }
    let d = domain_of(audit, &members.first()?.name)?;
    let name = file.file_name().map_or_else(
        || file.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let sources = members.iter().map(|m| m.name.clone()).collect();
    Some(moved_by(name, Scope::File(file.to_path_buf()), sources, d))
}

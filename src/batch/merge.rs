//! `trajdrift merge`: the per-mission results and run records of several folders (the shards of a
//! cluster run), checked before they are summarised. A merge knows when its set is incomplete:
//!
//! - a file it cannot read or parse (a result cut short by a full disk, a file too large to be one)
//!   is named, never skipped in silence; a JSON file that is not trajdrift's is skipped with a note;
//! - a mission name that is not a safe file name (`javascript:…`, `../../etc/passwd`), or that differs
//!   from its file's name, is refused: names from JSON become links in `summary.html`;
//! - the run records ([`super::identity::RunRecord`]) must agree (same parameters, same missions, same
//!   shard count), every shard of the run must be there and finished, every mission of the run must
//!   have its result, computed with the run's parameters, and no result may belong to another run.
//!
//! Any of these is a problem: `merge` names each and exits 1 without writing a summary, or, with
//! `--allow-partial`, writes the summary marked partial with the problems listed.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use serde::Deserialize;

use super::identity::{RunRecord, RunStatus, RUN_KIND};
use super::manifest::valid_name;
use super::run::MAX_RESULT_BYTES;
use super::summary::{MissionResult, MISSION_KIND};
use crate::error::{Error, Result};
use crate::report::escape::escape;

/// What the folders hold, read and checked.
#[derive(Debug, Clone, Default)]
pub struct MergeSet {
    /// The results to summarise, in name order (results that belong to no run of the set left out).
    pub results: Vec<MissionResult>,
    /// Every `*.json` read (the merge's own outputs must not overwrite one).
    pub files: Vec<PathBuf>,
    /// What is wrong with the set, one line each; empty for a complete, consistent set.
    pub problems: Vec<String>,
    /// JSON files that are not trajdrift's, skipped.
    pub skipped: Vec<PathBuf>,
}

/// Only the `kind` of a JSON file (the rest is parsed without being kept).
#[derive(Deserialize)]
struct Probe {
    kind: Option<String>,
}

/// Whether a file name is one of the summaries `batch` and `merge` write.
fn is_summary(name: &str) -> bool {
    name == "summary.json"
        || name
            .strip_prefix("summary-shard-")
            .is_some_and(|r| r.ends_with(".json"))
}

/// Reads every `*.json` of `dirs` and checks the set (see the module documentation).
pub fn read_set(dirs: &[PathBuf]) -> Result<MergeSet> {
    let mut set = MergeSet::default();
    let mut runs: Vec<(PathBuf, RunRecord)> = Vec::new();
    let mut found: BTreeMap<String, (PathBuf, MissionResult)> = BTreeMap::new();
    for dir in dirs {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| Error::io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| !n.starts_with('.') && !is_summary(n))
            })
            .collect();
        paths.sort();
        for p in paths {
            set.files.push(p.clone());
            let shown = p.display().to_string();
            let bytes =
                match crate::sources::input::read_bounded(&p, MAX_RESULT_BYTES, "mission result") {
                    Ok(b) => b,
                    Err(e) => {
                        set.problems.push(format!("{}", escape(&e.to_string())));
                        continue;
                    }
                };
            let kind = match serde_json::from_slice::<Probe>(&bytes) {
                Ok(p) => p.kind,
                Err(e) => {
                    set.problems.push(format!(
                        "{shown}: cannot parse ({e}): a result cut short? Re-run its mission"
                    ));
                    continue;
                }
            };
            match kind.as_deref() {
                Some(MISSION_KIND) => match serde_json::from_slice::<MissionResult>(&bytes) {
                    Ok(r) => check_result(&mut set, &mut found, p, r),
                    Err(e) => set.problems.push(format!(
                        "{shown}: not a valid mission result ({e}); re-run its mission"
                    )),
                },
                Some(RUN_KIND) => match serde_json::from_slice::<RunRecord>(&bytes) {
                    Ok(r) => runs.push((p, r)),
                    Err(e) => set
                        .problems
                        .push(format!("{shown}: not a valid run record ({e})")),
                },
                _ => set.skipped.push(p),
            }
        }
    }
    check_runs(&mut set, &runs, &mut found, dirs);
    set.results = found.into_values().map(|(_, r)| r).collect();
    if set.results.is_empty() && set.problems.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "no mission result (*.json from `trajdrift batch`) in {}",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(set)
}

/// A result's name checks: a safe name, its file's name, found once.
fn check_result(
    set: &mut MergeSet,
    found: &mut BTreeMap<String, (PathBuf, MissionResult)>,
    p: PathBuf,
    r: MissionResult,
) {
    let shown = p.display().to_string();
    if !valid_name(&r.mission) {
        set.problems.push(format!(
            "{shown}: mission name `{}` is not a valid mission name (letters, digits, `.`, `_`, `-`; not starting with `.`); the file was not written by `trajdrift batch`",
            escape(&r.mission)
        ));
        return;
    }
    let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
    if stem != r.mission {
        set.problems.push(format!(
            "{shown}: holds mission `{}`, not `{stem}` (a renamed or copied result?)",
            r.mission
        ));
        return;
    }
    if let Some((other, _)) = found.get(&r.mission) {
        set.problems.push(format!(
            "mission `{}` appears twice: {} and {shown}",
            r.mission,
            other.display()
        ));
        return;
    }
    found.insert(r.mission.clone(), (p, r));
}

/// The run records against each other and against the results.
fn check_runs(
    set: &mut MergeSet,
    runs: &[(PathBuf, RunRecord)],
    found: &mut BTreeMap<String, (PathBuf, MissionResult)>,
    dirs: &[PathBuf],
) {
    let Some((first_path, first)) = runs.first() else {
        set.problems.push(format!(
            "no run record (trajdrift-run*.json) in {}: cannot tell whether the results are complete (results of an older trajdrift, or copied without it)",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
        return;
    };
    // Runs of the same missions with the same parameters are one batch however it was sharded (an
    // unsharded run and the shards of another cover the same results).
    for (p, r) in &runs[1..] {
        if r.parameters == first.parameters {
            continue;
        }
        let what = if r.missions.keys().eq(first.missions.keys()) {
            "mismatched parameters"
        } else {
            "different missions"
        };
        set.problems.push(format!(
            "{} and {} are records of different runs: {what}; merge the shards of one run",
            first_path.display(),
            p.display()
        ));
    }
    let same: Vec<&(PathBuf, RunRecord)> = runs
        .iter()
        .filter(|(_, r)| r.parameters == first.parameters)
        .collect();
    unfinished_runs(set, &same);
    let asked: BTreeSet<&String> = same.iter().flat_map(|(_, r)| &r.selected).collect();
    missing_shards(set, first, &same, &asked);
    check_results(set, first, &asked, found);
}

/// A record still `running` whose missions no complete record covers: killed or still running.
fn unfinished_runs(set: &mut MergeSet, same: &[&(PathBuf, RunRecord)]) {
    let covered: BTreeSet<&String> = same
        .iter()
        .filter(|(_, r)| r.status == RunStatus::Complete)
        .flat_map(|(_, r)| &r.selected)
        .collect();
    for (p, r) in same {
        if r.status == RunStatus::Running && r.selected.iter().any(|m| !covered.contains(m)) {
            set.problems.push(format!(
                "{}: its run did not finish (killed, or still running): re-run it{}",
                p.display(),
                r.shard.map_or(String::new(), |s| format!(
                    " (--shard {}/{})",
                    s.index, s.count
                ))
            ));
        }
    }
}

/// Missions of the batch no record asked for: the shards that would have are missing.
fn missing_shards(
    set: &mut MergeSet,
    first: &RunRecord,
    same: &[&(PathBuf, RunRecord)],
    asked: &BTreeSet<&String>,
) {
    if first.missions.keys().all(|m| asked.contains(m)) {
        return;
    }
    let mut counts: Vec<usize> = same
        .iter()
        .filter_map(|(_, r)| r.shard.map(|s| s.count))
        .collect();
    counts.sort_unstable();
    counts.dedup();
    for count in counts {
        for i in 1..=count {
            if !same
                .iter()
                .any(|(_, r)| r.shard.is_some_and(|s| s.index == i && s.count == count))
            {
                set.problems.push(format!(
                    "missing shard {i} of {count} (no trajdrift-run-shard-{i}-of-{count}.json): run it with --shard {i}/{count}"
                ));
            }
        }
    }
}

/// Each asked mission has a result computed with the run's parameters; results of missions the
/// run does not hold are leftovers, named and dropped.
fn check_results(
    set: &mut MergeSet,
    first: &RunRecord,
    asked: &BTreeSet<&String>,
    found: &mut BTreeMap<String, (PathBuf, MissionResult)>,
) {
    for m in first.missions.keys() {
        if asked.contains(m) && !found.contains_key(m) {
            set.problems.push(format!(
                "mission `{m}` has no result ({m}.json is missing): re-run the run with --skip-existing"
            ));
        }
    }
    let mut leftovers = Vec::new();
    for (name, (p, r)) in found.iter() {
        match first.missions.get(name) {
            None => {
                set.problems.push(format!(
                    "{}: mission `{name}` is not in the run (a leftover of an earlier run?)",
                    p.display()
                ));
                leftovers.push(name.clone());
            }
            Some(params) if r.fingerprint.as_ref().map(|f| &f.parameters) != Some(params) => {
                set.problems.push(format!(
                    "{}: mission `{name}` was computed with other parameters than the run's (a leftover of an earlier run?); re-run it",
                    p.display()
                ))
            }
            Some(_) => {}
        }
    }
    for name in leftovers {
        found.remove(&name);
    }
}

//! `trajdrift topics`: what a recording holds and which channels trajdrift reads as trajectories.
//! A recording cut short is said (exit 3), and one without any channel is called empty.

use std::fmt::Write;

use anyhow::Result;

use trajdrift::output::{is_stdout, write_json, OutputGuard};
use trajdrift::report::escape::escape;
use trajdrift::sources::tf_frames::FramePair;
use trajdrift::sources::{TopicInfo, Warning};

use crate::cli::args::TopicsArgs;
use crate::cli::{EXIT_OK, EXIT_WARNING};

/// Runs the command; returns the exit code.
pub fn run(a: TopicsArgs) -> Result<u8> {
    let mut guard = OutputGuard::new(&a.recording);
    if let Some(out) = &a.json {
        guard.claim("--json", out)?;
    }
    let source = trajdrift::sources::open_all(&a.recording)?;
    let files = mission_files(&a.recording)?;
    let mut topics = source.topics()?;
    // TF frames are not in any index: one more pass, over the TF channels only; it reads every record,
    // so it also finds where a recording is cut short.
    let (pairs, mut warnings) = source.frame_pairs_checked(&|_| {})?;
    if topics.is_empty() && warnings.is_empty() {
        warnings.push(Warning {
            code: trajdrift::diag::WarningCode::EmptyRecording,
            message: format!(
                "{}: empty recording: it holds no channel and no message",
                a.recording[0].display()
            ),
        });
    }
    trajdrift::sources::tf_frames::attach(&mut topics, &pairs);
    let presets = trajdrift::eval::preset::matching(&topics);
    let to_stdout = a.json.as_deref().is_some_and(is_stdout);
    if let Some(path) = &a.json {
        let mut listing =
            serde_json::json!({ "topics": topics, "presets": presets, "warnings": warnings });
        if !files.is_empty() {
            listing["files"] = serde_json::to_value(&files)?;
        }
        guard.check("--json", path)?;
        write_json(path, &listing)?;
    }
    if !to_stdout {
        crate::cli::emit(&render(&topics, &pairs, &presets, &files))?;
    }
    for w in &warnings {
        crate::cli::warn(w);
    }
    Ok(if warnings.is_empty() {
        EXIT_OK
    } else {
        EXIT_WARNING
    })
}

/// The table of channels, the presets matching and the TF frame pairs; names from the file escaped.
fn render(
    topics: &[TopicInfo],
    pairs: &[FramePair],
    presets: &[String],
    files: &[MissionFile],
) -> String {
    let mut s = String::new();
    let width = column(topics.iter().map(|t| escape(&t.topic).chars().count()), 5);
    let type_width = column(
        topics.iter().map(|t| escape(&t.type_name).chars().count()),
        4,
    );
    let _ = writeln!(
        s,
        "{:<width$}  {:<type_width$} {:>9}  trajectory",
        "topic", "type", "messages"
    );
    for t in topics {
        let readable = if t.readable {
            "yes"
        } else if !t.frame_pairs.is_empty() {
            "as /tf:PARENT:CHILD"
        } else {
            "no"
        };
        let _ = writeln!(
            s,
            "{:<width$}  {:<type_width$} {:>9}  {readable}",
            escape(&t.topic),
            escape(&t.type_name),
            t.message_count
        );
    }
    let _ = writeln!(s, "presets matching: {}", presets_line(presets));
    if !files.is_empty() {
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "files of the mission (topics above are merged across them):"
        );
        for f in files {
            let names: Vec<String> = f.topics.iter().map(|t| escape(t).into_owned()).collect();
            let _ = writeln!(s, "  {}: {}", escape(&f.path), names.join(", "));
        }
    }
    if !pairs.is_empty() {
        render_pairs(&mut s, topics, pairs);
    }
    s
}

fn render_pairs(s: &mut String, topics: &[TopicInfo], pairs: &[FramePair]) {
    let label = |p: &FramePair| format!("{} → {}", escape(&p.parent), escape(&p.child));
    let width = column(pairs.iter().map(|p| label(p).chars().count()), 12);
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "TF frame pairs (pass /tf:PARENT:CHILD as a topic; chains compose several edges):"
    );
    let _ = writeln!(
        s,
        "{:<width$}  {:<8} {:>9}  topic to pass",
        "parent → child", "kind", "edges"
    );
    for p in pairs {
        let _ = writeln!(
            s,
            "{:<width$}  {:<8} {:>9}  {}",
            label(p),
            if p.is_static { "static" } else { "dynamic" },
            p.count,
            escape(&p.chain)
        );
    }
    let chains: Vec<String> = topics
        .iter()
        .flat_map(|t| &t.tf_chains)
        .map(|c| escape(c).into_owned())
        .collect();
    if !chains.is_empty() {
        let _ = writeln!(s, "TF chains root → leaf: {}", chains.join(", "));
    }
}

fn column(widths: impl Iterator<Item = usize>, min: usize) -> usize {
    widths.max().unwrap_or(min).max(min)
}

fn presets_line(presets: &[String]) -> String {
    if presets.is_empty() {
        "none".into()
    } else {
        format!("{} (use --preset NAME)", presets.join(", "))
    }
}

/// One file of a mission, as `topics` lists it.
#[derive(serde::Serialize)]
struct MissionFile {
    path: String,
    topics: Vec<String>,
}

/// The files of a mission (several paths, or a mission folder) with their topics; empty for one
/// recording.
fn mission_files(paths: &[std::path::PathBuf]) -> Result<Vec<MissionFile>> {
    let files = match paths {
        [one] if one.is_dir() && !one.join("metadata.yaml").is_file() => {
            trajdrift::sources::open::recordings_in(one)?
        }
        [_] => return Ok(Vec::new()),
        many => many.to_vec(),
    };
    files
        .iter()
        .map(|p| {
            let topics = trajdrift::sources::open(p)?.topics()?;
            Ok(MissionFile {
                path: p.display().to_string(),
                topics: topics.into_iter().map(|t| t.topic).collect(),
            })
        })
        .collect()
}

//! `trajdrift topics`: what a recording holds and which channels trajdrift reads as trajectories.

use anyhow::Result;

use trajdrift::report::output::write_output;

use crate::cli::args::TopicsArgs;
use crate::cli::EXIT_OK;

/// Runs the command; returns the exit code.
pub fn run(a: TopicsArgs) -> Result<u8> {
    let source = trajdrift::sources::open_all(&a.recording)?;
    let files = mission_files(&a.recording)?;
    let mut topics = source.topics()?;
    // TF frames are not in any index: one more pass, over the TF channels only.
    let pairs = source.frame_pairs(&|_| {})?;
    trajdrift::sources::tf_frames::attach(&mut topics, &pairs);
    let presets = trajdrift::eval::preset::matching(&topics);
    if let Some(path) = &a.json {
        let mut listing = serde_json::json!({ "topics": topics, "presets": presets });
        if !files.is_empty() {
            listing["files"] = serde_json::to_value(&files)?;
        }
        let mut bytes = serde_json::to_vec_pretty(&listing)?;
        bytes.push(b'\n');
        write_output(path, &bytes)?;
        if path.as_os_str() == "-" {
            return Ok(EXIT_OK);
        }
    }
    let width = topics
        .iter()
        .map(|t| t.topic.len())
        .max()
        .unwrap_or(5)
        .max(5);
    let type_width = topics
        .iter()
        .map(|t| t.type_name.len())
        .max()
        .unwrap_or(4)
        .max(4);
    println!(
        "{:<width$}  {:<type_width$} {:>9}  trajectory",
        "topic", "type", "messages"
    );
    for t in &topics {
        let readable = if t.readable {
            "yes"
        } else if !t.frame_pairs.is_empty() {
            "as /tf:PARENT:CHILD"
        } else {
            "no"
        };
        println!(
            "{:<width$}  {:<type_width$} {:>9}  {readable}",
            t.topic, t.type_name, t.message_count
        );
    }
    println!("presets matching: {}", presets_line(&presets));
    if !files.is_empty() {
        println!();
        println!("files of the mission (topics above are merged across them):");
        for f in &files {
            println!("  {}: {}", f.path, f.topics.join(", "));
        }
    }
    if !pairs.is_empty() {
        let width = pairs
            .iter()
            .map(|p| p.parent.len() + p.child.len() + 3)
            .max()
            .unwrap_or(0)
            .max(12);
        println!();
        println!(
            "TF frame pairs (pass /tf:PARENT:CHILD as a topic; chains compose several edges):"
        );
        println!(
            "{:<width$}  {:<8} {:>9}  topic to pass",
            "parent → child", "kind", "edges"
        );
        for p in &pairs {
            println!(
                "{:<width$}  {:<8} {:>9}  {}",
                format!("{} → {}", p.parent, p.child),
                if p.is_static { "static" } else { "dynamic" },
                p.count,
                p.chain
            );
        }
        let chains: Vec<&String> = topics.iter().flat_map(|t| &t.tf_chains).collect();
        if !chains.is_empty() {
            println!(
                "TF chains root → leaf: {}",
                chains
                    .iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    Ok(EXIT_OK)
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

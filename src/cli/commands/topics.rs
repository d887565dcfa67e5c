//! `trajdrift topics`: what a recording holds and which channels trajdrift reads as trajectories.

use anyhow::Result;

use trajdrift::report::output::write_output;

use crate::cli::args::TopicsArgs;
use crate::cli::EXIT_OK;

/// Runs the command; returns the exit code.
pub fn run(a: TopicsArgs) -> Result<u8> {
    let source = trajdrift::sources::open(&a.recording)?;
    let topics = source.topics()?;
    let presets = trajdrift::eval::preset::matching(&topics);
    if let Some(path) = &a.json {
        let listing = serde_json::json!({ "topics": topics, "presets": presets });
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
    println!(
        "{:<width$}  {:<36} {:>9}  trajectory",
        "topic", "type", "messages"
    );
    for t in &topics {
        println!(
            "{:<width$}  {:<36} {:>9}  {}",
            t.topic,
            t.type_name,
            t.message_count,
            if t.readable { "yes" } else { "no" }
        );
    }
    println!("presets matching: {}", presets_line(&presets));
    Ok(EXIT_OK)
}

fn presets_line(presets: &[String]) -> String {
    if presets.is_empty() {
        "none".into()
    } else {
        format!("{} (use --preset NAME)", presets.join(", "))
    }
}

//! `trajdrift man`: the manual, generated from the clap definitions (`clap_mangen`), so it can never
//! disagree with `--help`. Without `--out`, the main page (every command listed) goes to stdout; with
//! `--out DIR`, one page per command (`trajdrift.1`, `trajdrift-eval.1`, …), each written through the
//! one file writer.

use std::path::Path;

use anyhow::Result;
use clap::CommandFactory;
use clap_mangen::roff::{roman, Roff};
use clap_mangen::Man;

use trajdrift::output::{write_output, OutputGuard};

use crate::cli::args::{Cli, ManArgs};
use crate::cli::EXIT_OK;

/// Runs the command; returns the exit code.
pub fn run(a: ManArgs) -> Result<u8> {
    let mut cmd = Cli::command().disable_help_subcommand(true);
    cmd.build();
    match &a.out {
        None => crate::cli::emit(&page(&cmd)?)?,
        Some(dir) => {
            OutputGuard::default().claim_dir("--out", dir)?;
            std::fs::create_dir_all(dir).map_err(|e| trajdrift::Error::Output {
                path: dir.clone(),
                detail: e.to_string(),
            })?;
            write_pages(&cmd, dir)?;
        }
    }
    Ok(EXIT_OK)
}

/// Writes the page of `cmd` and of each of its commands into `dir`, printing each path.
fn write_pages(cmd: &clap::Command, dir: &Path) -> Result<()> {
    let name = Man::new(cmd.clone()).get_filename();
    let path = dir.join(name);
    write_output(&path, page(cmd)?.as_bytes())?;
    crate::cli::emit(&format!("{}\n", path.display()))?;
    for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
        write_pages(sub, dir)?;
    }
    Ok(())
}

/// One command's page: clap_mangen's sections (name, synopsis, description, options, commands,
/// version), then the sections of its `after_help` (examples, exit status) as headings with their
/// lines kept as written.
fn page(cmd: &clap::Command) -> Result<String> {
    let after = cmd.get_after_help().map(|t| t.to_string());
    let man = Man::new(cmd.clone().after_help(None::<&str>));
    let mut out = Vec::new();
    man.render(&mut out)?;
    let mut text = String::from_utf8_lossy(&out).into_owned();
    if let Some(after) = after {
        text.push_str(&sections(&after).to_roff());
    }
    Ok(text)
}

/// `Heading:` lines (unindented, ending in a colon) become `.SH HEADING`; the lines under a heading
/// are set without filling (`.nf`), so each example stays on its own line; blank lines between two
/// examples are kept, those before the next heading dropped.
fn sections(text: &str) -> Roff {
    let mut sections: Vec<(String, Vec<&str>)> = Vec::new();
    for line in text.lines() {
        if !line.starts_with(' ') && line.ends_with(':') {
            sections.push((line.trim_end_matches(':').to_uppercase(), Vec::new()));
        } else if let Some((_, lines)) = sections.last_mut() {
            lines.push(line);
        }
    }
    let mut roff = Roff::new();
    for (title, mut lines) in sections {
        while lines.last().is_some_and(|l| l.trim().is_empty()) {
            lines.pop();
        }
        roff.control("SH", [title.as_str()]);
        roff.control("nf", []);
        for line in lines {
            if line.trim().is_empty() {
                roff.control("sp", []);
            } else {
                roff.text([roman(line)]);
            }
        }
        roff.control("fi", []);
    }
    roff
}

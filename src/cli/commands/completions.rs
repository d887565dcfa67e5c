//! `trajdrift completions SHELL`: the shell's completion script, generated from the clap definitions
//! (`clap_complete`), to stdout. It is built in memory and printed through the one stdout writer, so
//! a closed pipe ends quietly.

use anyhow::Result;
use clap::CommandFactory;

use crate::cli::args::{Cli, CompletionsArgs};
use crate::cli::EXIT_OK;

/// Runs the command; returns the exit code.
pub fn run(a: CompletionsArgs) -> Result<u8> {
    let mut cmd = Cli::command();
    let mut script = Vec::new();
    clap_complete::generate(a.shell, &mut cmd, "trajdrift", &mut script);
    crate::cli::emit(&String::from_utf8_lossy(&script))?;
    Ok(EXIT_OK)
}

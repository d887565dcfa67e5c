//! `trajdrift validate`: the calibration table of the time alignment on simulated missions (see
//! `trajdrift::validate`).

use anyhow::Result;

use trajdrift::output::{is_stdout, write_json, OutputGuard};
use trajdrift::simulate::scenario::MissionKind;
use trajdrift::validate::{table, ValidateOptions};

use crate::cli::args::ValidateArgs;
use crate::cli::progress::ReadProgress;
use crate::cli::{emit, EXIT_OK};

/// Runs the command; returns the exit code.
pub fn run(a: ValidateArgs) -> Result<u8> {
    // The output claimed before any mission is simulated.
    let mut guard = OutputGuard::default();
    if let Some(path) = &a.json {
        guard.claim("--json", path)?;
    }
    let options = ValidateOptions {
        per_kind: a.missions as usize,
        kinds: a.kind.clone(),
        first_seed: a.seed,
    };
    let kinds = if options.kinds.is_empty() {
        MissionKind::ALL.len()
    } else {
        options.kinds.len()
    };
    let total = options.per_kind * kinds;
    let bar = ReadProgress::counting(total as u64, false, "missions");
    let grades = trajdrift::validate::run(&options, &|_, _| bar.inc());
    bar.finish();
    if let Some(path) = &a.json {
        guard.check("--json", path)?;
        write_json(path, &grades)?;
    }
    if !a.json.as_deref().is_some_and(is_stdout) {
        emit(&table(&grades))?;
    }
    Ok(EXIT_OK)
}

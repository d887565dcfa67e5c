//! `trajdrift validate`: the calibration table of the time alignment on simulated missions (see
//! `trajdrift::validate`).

use anyhow::Result;

use trajdrift::report::output::write_output;
use trajdrift::validate::{table, ValidateOptions};

use trajdrift::simulate::scenario::MissionKind;

use crate::cli::args::ValidateArgs;
use crate::cli::progress::ReadProgress;
use crate::cli::{emit, EXIT_OK};

/// Runs the command; returns the exit code.
pub fn run(a: ValidateArgs) -> Result<u8> {
    let options = ValidateOptions {
        per_kind: a.missions,
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
        let mut bytes = serde_json::to_vec_pretty(&grades)?;
        bytes.push(b'\n');
        write_output(path, &bytes)?;
    }
    if a.json.as_deref().is_none_or(|p| p.as_os_str() != "-") {
        emit(&table(&grades))?;
    }
    Ok(EXIT_OK)
}

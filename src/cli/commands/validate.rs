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
    if !a.like.is_empty() || a.reference_file.is_some() || a.estimate_file.is_some() {
        return like(&a, &mut guard);
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

/// `--like`: missions shaped like the user's recording.
fn like(a: &ValidateArgs, guard: &mut OutputGuard) -> Result<u8> {
    use trajdrift::eval::config::{EvalConfig, NamedInput};
    let files = trajdrift::audit::discover::expand_files(&a.like)?;
    let texts = a.reference_file.iter().chain(&a.estimate_file);
    *guard = OutputGuard::new(a.like.iter().chain(&files).chain(texts));
    if let Some(path) = &a.json {
        guard.claim("--json", path)?;
    }
    let reference = match (&a.reference, &a.reference_file) {
        (Some(t), _) => NamedInput::topic(t),
        (None, Some(f)) => NamedInput::file(&f.to_string_lossy()),
        (None, None) => {
            anyhow::bail!("validate --like needs --reference TOPIC or --reference-file FILE")
        }
    };
    let estimate = match (&a.estimate, &a.estimate_file) {
        (Some(t), _) => NamedInput::topic(t),
        (None, Some(f)) => NamedInput::file(&f.to_string_lossy()),
        (None, None) => {
            anyhow::bail!("validate --like needs --estimate TOPIC or --estimate-file FILE")
        }
    };
    let mut config = EvalConfig::new(a.like.first().cloned(), reference, vec![estimate]);
    config.more_recordings = a.like.iter().skip(1).cloned().collect();
    config.keep_orientations = true;
    config.validate()?;
    let total: u64 = a
        .like
        .iter()
        .chain(&a.reference_file)
        .chain(&a.estimate_file)
        .map(|p| trajdrift::sources::open::input_size(p))
        .sum();
    let read = ReadProgress::new(total, false);
    let shape = trajdrift::validate::like::recording_shape(&config, &|b| read.update(b));
    read.finish();
    let (shape, warnings) = shape?;
    let n = a.missions as usize;
    let bar = ReadProgress::counting(n as u64, false, "missions");
    let grades = trajdrift::validate::like::run_like(&shape, n, a.seed, &|_, _| bar.inc());
    bar.finish();
    if let Some(path) = &a.json {
        guard.check("--json", path)?;
        #[derive(serde::Serialize)]
        struct Like<'a> {
            shape: &'a trajdrift::simulate::like::Shape,
            missions: &'a [trajdrift::validate::MissionGrade],
        }
        write_json(
            path,
            &Like {
                shape: &shape,
                missions: &grades,
            },
        )?;
    }
    if !a.json.as_deref().is_some_and(is_stdout) {
        emit(&trajdrift::validate::like::like_table(&shape, &grades))?;
    }
    for w in &warnings {
        crate::cli::warn(w);
    }
    Ok(crate::cli::exit_code(&warnings))
}

//! `trajdrift eval`: time offset and Drift Error of one or more estimates against a reference.

use std::sync::Mutex;

use anyhow::Result;

use trajdrift::eval::config::{EvalConfig, LeverSpec, NamedInput};
use trajdrift::eval::preset::Preset;
use trajdrift::eval::roles;
use trajdrift::job::{self, JobEvent, JobOutputs};
use trajdrift::output::{is_stdout, write_json, OutputGuard};
use trajdrift::plot::{PictureOutputs, PlotFormat};
use trajdrift::render::table;

use crate::cli::args::{text_options, EvalArgs, PlotFormatArg};
use crate::cli::progress::ReadProgress;
use crate::cli::{EXIT_OK, EXIT_WARNING};

/// Builds the library's request from the flags, and the notes to print (a preset's estimates absent
/// from the recording).
pub fn config_from_args(a: &EvalArgs) -> Result<(EvalConfig, Vec<String>)> {
    let estimates: Vec<NamedInput> = a
        .estimate
        .iter()
        .map(|s| NamedInput::topic(s))
        .chain(a.estimate_file.iter().map(|s| NamedInput::file(s)))
        .collect();
    let preset = a.preset.as_deref().map(Preset::load).transpose()?;
    let roles = roles::resolve(
        &a.recording,
        roles::named_reference(a.reference.as_deref(), a.reference_file.as_deref()),
        estimates,
        preset.as_ref(),
        "give --reference TOPIC or --reference-file FILE",
    )?;
    let notes = roles.notes.clone();
    let mut c = roles.config(&a.recording, &[&a.params.0]);
    c.export_aligned = a.export_aligned.clone();
    c.text = text_options(&a.text)?;
    c.reference_lever = a
        .reference_lever
        .as_deref()
        .map(|s| LeverSpec::parse("--reference-lever", s))
        .transpose()?;
    c.estimate_levers = a
        .estimate_lever
        .iter()
        .map(|s| {
            // A name never holds `:` or `,`; `tf-static:` specs may hold `=` only after a `:`.
            let (name, l) = match s.split_once('=') {
                Some((n, l)) if !n.contains(':') && !n.contains(',') => (Some(n.to_string()), l),
                _ => (None, s.as_str()),
            };
            LeverSpec::parse("--estimate-lever", l).map(|l| (name, l))
        })
        .collect::<trajdrift::Result<_>>()?;
    Ok((c, notes))
}

/// `--plot DIR`, `--plot-format`, `--html FILE`.
pub fn pictures_from_args(a: &EvalArgs) -> PictureOutputs {
    PictureOutputs {
        plot_dir: a.plot.clone(),
        format: Some(match a.plot_format {
            PlotFormatArg::Svg => PlotFormat::Svg,
            PlotFormatArg::Png => PlotFormat::Png,
        }),
        html: a.html.clone(),
    }
}

/// The output guard of the command: every input (the recordings, text files, KITTI times, a preset
/// file) and every output claimed — `--json`, `--annotate`, `--export-aligned`, `--html`, `--plot`
/// and each figure — before any work, so that an output over an input or over another output is
/// refused (exit 2) while nothing has been read or written.
pub fn claim_outputs(
    a: &EvalArgs,
    config: &EvalConfig,
    pictures: &PictureOutputs,
) -> Result<OutputGuard> {
    let mut guard = config.output_guard();
    if let Some(p) = a.preset.as_deref().map(std::path::Path::new) {
        if p.is_file() {
            guard.add(p);
        }
    }
    if let Some(out) = &a.json {
        guard.claim("--json", out)?;
    }
    if let Some(out) = &a.annotate {
        guard.claim("--annotate", out)?;
    }
    config.claim_outputs(&mut guard)?;
    let names: Vec<&str> = config.estimates.iter().map(|e| e.name.as_str()).collect();
    pictures.claim(&mut guard, &names)?;
    Ok(guard)
}

/// Runs the command; returns the exit code.
pub fn run(a: EvalArgs) -> Result<u8> {
    let (config, notes) = config_from_args(&a)?;
    if !a.quiet {
        for n in &notes {
            eprintln!("note: {}", trajdrift::report::escape::escape(n));
        }
    }
    let outputs = JobOutputs {
        annotate: a.annotate.clone(),
        force: a.force,
        pictures: pictures_from_args(&a),
    };
    let guard = claim_outputs(&a, &config, &outputs.pictures)?;
    // Refuse before the evaluation pass rather than after it.
    job::check(&config, &outputs)?;
    let total: u64 = config
        .recordings()
        .iter()
        .map(|p| trajdrift::sources::open::input_size(p))
        .sum();
    // One progress bar per pass over the recording, shown while that pass runs.
    let bar: Mutex<Option<ReadProgress>> = Mutex::new(None);
    let done = job::run(&config, &outputs, &|event| {
        let mut bar = bar.lock().unwrap_or_else(|e| e.into_inner());
        match event {
            JobEvent::Read { bytes, .. } => bar
                .get_or_insert_with(|| ReadProgress::new(total, a.quiet))
                .update(bytes),
            JobEvent::PassDone => {
                if let Some(b) = bar.take() {
                    b.finish();
                }
            }
        }
    })?;
    if let (Some(annotated), false) = (&done.annotated, a.quiet) {
        eprintln!(
            "wrote {} ({} input messages copied, {} added)",
            annotated.path.display(),
            annotated.copy.messages,
            annotated.counts.values().sum::<u64>()
        );
    }
    if !a.quiet {
        for path in &done.pictures {
            eprintln!("wrote {}", path.display());
        }
    }
    let report = done.report;
    let json_to_stdout = a.json.as_deref().is_some_and(is_stdout);
    if let Some(path) = &a.json {
        guard.check("--json", path)?;
        write_json(path, &report)?;
    }
    let table = !a.quiet && !json_to_stdout;
    if table {
        crate::cli::emit(&table::render(&report))?;
    }
    // The table ends with the warnings; a terminal showing it needs them only once. Otherwise
    // (quiet, JSON on stdout, stdout redirected) they go to stderr, where the user sees them.
    if !(table && std::io::IsTerminal::is_terminal(&std::io::stdout())) {
        for w in &report.warnings {
            crate::cli::warn(w);
        }
    }
    Ok(if report.warnings.is_empty() {
        EXIT_OK
    } else {
        EXIT_WARNING
    })
}

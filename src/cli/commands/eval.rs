//! `trajdrift eval`: time offset and Drift Error of one or more estimates against a reference.

use anyhow::{anyhow, Result};

use trajdrift::annotate::annotate;
use trajdrift::eval::config::{EvalConfig, LeverSpec, NamedInput};
use trajdrift::eval::evaluate_with_inputs;
use trajdrift::eval::parameters::Parameters;
use trajdrift::eval::preset::Preset;
use trajdrift::output::{is_stdout, write_json, OutputGuard};
use trajdrift::plot::{PictureOutputs, PlotFormat, Trajectories};
use trajdrift::render::table;

use crate::cli::args::{text_options, EvalArgs, PlotFormatArg};
use crate::cli::progress::ReadProgress;
use crate::cli::{EXIT_OK, EXIT_WARNING};

/// Builds the library's request from the flags, and the notes to print (a preset's estimates absent
/// from the recording).
pub fn config_from_args(a: &EvalArgs) -> Result<(EvalConfig, Vec<String>)> {
    let reference = match (&a.reference, &a.reference_file) {
        (Some(t), _) => Some(NamedInput::topic(t)),
        (None, Some(f)) => Some(NamedInput::file(&f.to_string_lossy())),
        (None, None) => None,
    };
    let estimates: Vec<NamedInput> = a
        .estimate
        .iter()
        .map(|s| NamedInput::topic(s))
        .chain(a.estimate_file.iter().map(|s| NamedInput::file(s)))
        .collect();
    let preset = a.preset.as_deref().map(Preset::load).transpose()?;
    let mut notes = Vec::new();
    let (reference, estimates) = match &preset {
        Some(p) => {
            let s = p.select_in(&a.recording, reference, estimates)?;
            notes.extend(s.skipped.iter().map(|n| {
                format!(
                    "preset {}: estimate {n} is not in the recording, skipped",
                    p.name
                )
            }));
            (s.reference, s.estimates)
        }
        None => (
            reference.ok_or_else(|| anyhow!("give --reference TOPIC or --reference-file FILE"))?,
            estimates,
        ),
    };
    let mut c = EvalConfig::new(a.recording.first().cloned(), reference, estimates);
    c.more_recordings = a.recording.iter().skip(1).cloned().collect();
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
    let preset_parameters = preset.map(|p| p.parameters).unwrap_or_default();
    c.params = Parameters::layered([&preset_parameters, &a.params.0]);
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
    let (mut config, notes) = config_from_args(&a)?;
    // The annotated recording's aligned poses carry the estimate's orientation.
    config.keep_orientations = a.annotate.is_some();
    if !a.quiet {
        for n in &notes {
            eprintln!("note: {}", trajdrift::report::escape::escape(n));
        }
    }
    let pictures = pictures_from_args(&a);
    let guard = claim_outputs(&a, &config, &pictures)?;
    if let Some(out) = &a.annotate {
        // Refuse before the evaluation pass rather than after it.
        trajdrift::annotate::check_annotate(&config, out, a.force)?;
    }
    let total: u64 = config
        .recordings()
        .iter()
        .map(|p| trajdrift::sources::open::input_size(p))
        .sum();
    let progress = ReadProgress::new(total, a.quiet);
    let result = evaluate_with_inputs(&config, &|b| progress.update(b));
    progress.finish();
    let (report, inputs) = result?;
    if let Some(out) = &a.annotate {
        let progress = ReadProgress::new(total, a.quiet);
        let done = annotate(&config, &report, &inputs, out, a.force, &|b| {
            progress.update(b)
        });
        progress.finish();
        let done = done?;
        if !a.quiet {
            eprintln!(
                "wrote {} ({} input messages copied, {} added)",
                done.path.display(),
                done.copy.messages,
                done.counts.values().sum::<u64>()
            );
        }
    }
    let estimates = inputs.named_estimates();
    let trajectories = Trajectories {
        reference: &inputs.reference.trajectory,
        estimates: &estimates,
    };
    for path in pictures.write(&report, trajectories)? {
        if !a.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
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

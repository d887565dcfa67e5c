//! `trajdrift eval`: time offset and Drift Error of one or more estimates against a reference.

use anyhow::{anyhow, Result};

use trajdrift::align::time_offset::OffsetMethod;
use trajdrift::annotate::annotate;
use trajdrift::eval::config::{EvalConfig, LeverSpec, NamedInput, Platform};
use trajdrift::eval::evaluate_with_inputs;
use trajdrift::eval::preset::Preset;
use trajdrift::metrics::lever::LeverCorrection;
use trajdrift::report::table;
use trajdrift::sources::StampSource;

use crate::cli::args::{
    parse_triple, text_options, EvalArgs, LeverCorrectionArg, OffsetMethodArg, PlatformArg,
    StampArg,
};
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
            let s = p.select_in(a.recording.as_deref(), reference, estimates)?;
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
    let mut c = EvalConfig::new(a.recording.clone(), reference, estimates);
    c.stamp = match a.stamp {
        StampArg::Header => StampSource::Header,
        StampArg::Log => StampSource::Log,
    };
    c.origin = a
        .origin
        .as_deref()
        .map(|s| parse_triple("--origin", s))
        .transpose()
        .map_err(trajdrift::Error::InvalidArgument)?;
    c.platform = match a.platform {
        PlatformArg::Legged => Platform::Legged,
        PlatformArg::Wheeled => Platform::Wheeled,
        PlatformArg::Auto => Platform::Auto,
    };
    c.eps_min_m = a.eps_min;
    c.curvature_eps_m = a.curvature_eps;
    c.path_eps_m = a.path_eps;
    c.theta_max_rad = a.theta_max;
    if let Some(v) = a.dt_max {
        c.dt_max_s = v;
        c.curvature_dt_max_s = Some(v);
    }
    c.windows_m = a.window.clone();
    c.overlap = a.overlap;
    c.lever_correction = match a.lever_correction {
        LeverCorrectionArg::Paper => LeverCorrection::Paper,
        LeverCorrectionArg::None => LeverCorrection::None,
        LeverCorrectionArg::Fit => LeverCorrection::Fit,
    };
    c.lever_arm_m = a.lever_arm;
    c.offset_method = match a.offset_method {
        OffsetMethodArg::Curvature => OffsetMethod::Curvature,
        OffsetMethodArg::Speed => OffsetMethod::Speed,
        OffsetMethodArg::SignedCurvature => OffsetMethod::SignedCurvature,
        OffsetMethodArg::Auto => OffsetMethod::Auto,
    };
    c.max_offset_s = a.max_offset;
    c.grid_s = a.grid;
    c.time_offset_s = a.time_offset;
    c.t_start = a.t_start;
    c.t_end = a.t_end;
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
    if let Some(p) = &preset {
        p.apply_parameters(&mut c, &a.given)?;
    }
    Ok((c, notes))
}

/// Runs the command; returns the exit code.
pub fn run(a: EvalArgs) -> Result<u8> {
    let (config, notes) = config_from_args(&a)?;
    if !a.quiet {
        for n in &notes {
            eprintln!("note: {}", trajdrift::report::escape::escape(n));
        }
    }
    let guard = config.output_guard();
    if let Some(out) = &a.json {
        guard.check("--json", out)?;
    }
    if let (Some(out), Some(rec)) = (&a.annotate, &config.recording) {
        // Refuse before the evaluation pass rather than after it.
        trajdrift::annotate::check_output(rec, out, a.force)?;
    }
    let total = config
        .recording
        .as_ref()
        .and_then(|p| std::fs::metadata(p).ok())
        .map_or(0, |m| m.len());
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
    let json_to_stdout = a.json.as_deref().is_some_and(|p| p.as_os_str() == "-");
    if let Some(path) = &a.json {
        let mut bytes = serde_json::to_vec_pretty(&report)?;
        bytes.push(b'\n');
        guard.write("--json", path, &bytes)?;
    }
    if !a.quiet && !json_to_stdout {
        crate::cli::emit(&table::render(&report))?;
    }
    for w in &report.warnings {
        crate::cli::warn(&w.code, &w.message);
    }
    Ok(if report.warnings.is_empty() {
        EXIT_OK
    } else {
        EXIT_WARNING
    })
}

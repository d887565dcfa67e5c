//! `trajdrift sweep`: the evaluation over one parameter's values; writes DIR/sweep.csv and
//! DIR/sweep.svg and prints the table.

use anyhow::{anyhow, Result};

use trajdrift::eval::sweep::{parse_values, run_sweep, SweepParam};
use trajdrift::output::write_output;
use trajdrift::plot::sweep::SweepFigure;
use trajdrift::plot::{Figure, FigureData, PlotFormat};

use crate::cli::args::{SweepArgs, SweepParamArg};
use crate::cli::commands::eval::config_from_args;
use crate::cli::progress::ReadProgress;
use crate::cli::EXIT_WARNING;

fn param(p: SweepParamArg) -> SweepParam {
    match p {
        SweepParamArg::EpsMin => SweepParam::EpsMin,
        SweepParamArg::CurvatureEps => SweepParam::CurvatureEps,
        SweepParamArg::PathEps => SweepParam::PathEps,
        SweepParamArg::Window => SweepParam::Window,
        SweepParamArg::LeverArm => SweepParam::LeverArm,
        SweepParamArg::Overlap => SweepParam::Overlap,
        SweepParamArg::TimeOffset => SweepParam::TimeOffset,
    }
}

/// Runs the command; returns the exit code.
pub fn run(a: SweepArgs) -> Result<u8> {
    let e = &a.eval;
    if e.annotate.is_some()
        || e.export_aligned.is_some()
        || e.plot.is_some()
        || e.html.is_some()
        || e.json.is_some()
    {
        return Err(anyhow!(trajdrift::Error::InvalidArgument(
            "sweep writes DIR/sweep.csv and DIR/sweep.svg only: drop --annotate, --export-aligned, --plot, --html and --json".into()
        )));
    }
    let (config, notes) = config_from_args(e)?;
    if !e.quiet {
        for n in &notes {
            eprintln!("note: {}", trajdrift::report::escape::escape(n));
        }
    }
    let param = param(a.param);
    let values = parse_values(&a.values)?;
    // DIR/sweep.csv and DIR/sweep.svg are claimed before any work: never over an input.
    let mut guard = config.output_guard();
    if let Some(p) = e.preset.as_deref().map(std::path::Path::new) {
        if p.is_file() {
            guard.add(p);
        }
    }
    guard.claim_dir("--out", &a.out)?;
    guard.claim("--out", &a.out.join("sweep.csv"))?;
    guard.claim("--out", &a.out.join("sweep.svg"))?;
    std::fs::create_dir_all(&a.out).map_err(|err| trajdrift::Error::output(&a.out, &err))?;
    let total = config
        .recording
        .as_ref()
        .and_then(|p| std::fs::metadata(p).ok())
        .map_or(0, |m| m.len());
    let reading = ReadProgress::new(total, e.quiet);
    let progress = ReadProgress::counting(values.len() as u64, e.quiet, param.as_str());
    let sweep = run_sweep(&config, param, &values, &|b| reading.update(b), &|| {
        reading.finish();
        progress.inc()
    });
    reading.finish();
    progress.finish();
    let sweep = sweep?;
    let csv = sweep.to_csv()?;
    write_output(&a.out.join("sweep.csv"), csv.as_bytes())?;
    let title = format!("Drift Error against {}", param.as_str());
    let figure = Figure {
        name: "sweep".into(),
        title: title.clone(),
        data: FigureData::Sweep(SweepFigure::from_sweep(&sweep, title)),
    };
    figure.write(&a.out, PlotFormat::Svg)?;
    if !e.quiet {
        print!("{csv}");
        eprintln!(
            "wrote {} and {}",
            a.out.join("sweep.csv").display(),
            a.out.join("sweep.svg").display()
        );
    }
    for r in sweep.rows.iter().filter(|r| r.error.is_some()) {
        eprintln!(
            "warning: {} = {}: {}",
            param.as_str(),
            r.value,
            trajdrift::report::escape::escape(r.error.as_deref().unwrap_or(""))
        );
    }
    for w in &sweep.warnings {
        crate::cli::warn(w);
    }
    Ok(if sweep.rows.iter().any(|r| r.error.is_some()) {
        EXIT_WARNING
    } else {
        crate::cli::exit_code(&sweep.warnings)
    })
}

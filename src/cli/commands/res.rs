//! `trajdrift res`: evo_res over result files of evo or trajdrift (`trajdrift::evo::res`), plus
//! `--runs` (mean ± 95 % interval over repeated runs) and `--compare A B` (paired comparison).

use anyhow::Result;

use trajdrift::evo::res::{
    check_unique, compare_report, figures, load, merge, render, runs_report, table_file,
    title_conflicts, TableFormat,
};
use trajdrift::output::OutputGuard;

use crate::cli::evo_args::{ignored_notes, ResArgs};
use crate::cli::evo_log::EvoLog;
use crate::cli::{EXIT_OK, EXIT_WARNING};

/// Runs the command; returns the exit code.
pub fn run(a: ResArgs) -> Result<u8> {
    let log = EvoLog::new(&a.usability, &a);
    for note in ignored_notes(&a.viewer.given()) {
        log.warn(&note);
    }
    if a.result_files.is_empty() {
        return Err(trajdrift::Error::InvalidArgument(
            "give one or more result files (RESULT.zip of --save_results)".into(),
        )
        .into());
    }
    let mut guard = OutputGuard::new(a.result_files.iter().chain(&a.usability.config));
    for (flag, out) in [
        ("--save_table", a.save_table.as_deref()),
        ("--logfile", a.usability.logfile.as_deref()),
    ] {
        if let Some(out) = out {
            guard.claim(flag, out)?;
        }
    }
    let loaded = load(&a.result_files, a.use_filenames)?;
    log.detail(&format!("{} result files read", loaded.len()));
    let results = if a.merge {
        vec![merge(&loaded)?]
    } else {
        loaded.clone()
    };
    check_unique(&results)?;
    let mut code = EXIT_OK;
    if !a.ignore_title && !a.usability.no_warnings {
        for (file, title) in title_conflicts(&results) {
            code = EXIT_WARNING;
            log.warn(&format!(
                "warning [mismatching_titles]: {}: title {:?} differs from the first file's; only the first is printed (--ignore_title to just aggregate)",
                file.display(),
                title
            ));
        }
    }
    log.result(&render(&results, a.ignore_title))?;
    if let Some(path) = &a.save_table {
        guard.write(
            "--save_table",
            path,
            table_file(&results, TableFormat::of(path)).as_bytes(),
        )?;
        log.detail(&format!("table written to {}", path.display()));
    }
    if a.runs {
        log.result(&runs_report(&loaded))?;
    }
    if let Some(c) = &a.compare {
        let (text, _) = compare_report(&loaded, &c[0], &c[1], &a.compare_stat)?;
        log.result(&text)?;
    }
    if a.plot || a.save_plot.is_some() {
        let figs = figures(&results, a.ignore_title, a.use_rel_time, a.plot_markers);
        let base = a.result_files[0].with_extension("");
        if super::metric::write_figures(&log, &guard, a.save_plot.as_deref(), &base, &figs)? {
            code = EXIT_WARNING;
        }
    }
    log.finish(&guard)?;
    Ok(code)
}

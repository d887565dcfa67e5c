//! evo's `-v`, `--silent`, `--debug` and `--logfile` for `ape`, `rpe`, `res` and `traj`: results on
//! stdout unless `--silent`, details (inputs, association, alignment, files written) on stderr with
//! `-v` or `--debug` (which adds the parsed arguments), warnings always on stderr, and everything
//! also into `--logfile FILE` (written through the output guard when the command ends).

use std::cell::RefCell;
use std::path::PathBuf;

use trajdrift::output::OutputGuard;

use crate::cli::evo_args::EvoUsability;

/// Where a command's messages go.
#[derive(Debug, Default)]
pub struct EvoLog {
    verbose: bool,
    silent: bool,
    logfile: Option<PathBuf>,
    text: RefCell<String>,
}

impl EvoLog {
    /// The log of the usability flags `u`; with `--debug`, `args` (the parsed command line) first.
    pub fn new(u: &EvoUsability, args: &dyn std::fmt::Debug) -> EvoLog {
        let log = EvoLog {
            verbose: u.verbose || u.debug,
            silent: u.silent,
            logfile: u.logfile.clone(),
            text: RefCell::new(String::new()),
        };
        if u.debug {
            log.detail(&format!("arguments: {args:#?}"));
        }
        log
    }

    /// A result: stdout unless `--silent`.
    pub fn result(&self, text: &str) -> trajdrift::Result<()> {
        self.text.borrow_mut().push_str(text);
        if self.silent {
            return Ok(());
        }
        crate::cli::emit(text)
    }

    /// A detail: stderr with `-v`/`--debug`.
    pub fn detail(&self, text: &str) {
        let mut t = self.text.borrow_mut();
        t.push_str(text);
        t.push('\n');
        if self.verbose {
            eprintln!("{text}");
        }
    }

    /// What was written where: stderr unless `--silent`.
    pub fn note(&self, text: &str) {
        let mut t = self.text.borrow_mut();
        t.push_str(text);
        t.push('\n');
        if !self.silent {
            eprintln!("{}", trajdrift::report::escape::escape_line(text));
        }
    }

    /// A warning or note: always stderr.
    pub fn warn(&self, text: &str) {
        let mut t = self.text.borrow_mut();
        t.push_str(text);
        t.push('\n');
        eprintln!("{}", trajdrift::report::escape::escape_line(text));
    }

    /// Writes `--logfile` (checked against the inputs).
    pub fn finish(&self, guard: &OutputGuard) -> trajdrift::Result<()> {
        if let Some(path) = &self.logfile {
            guard.write("--logfile", path, self.text.borrow().as_bytes())?;
        }
        Ok(())
    }
}

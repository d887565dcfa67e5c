//! The reading progress bar: shown on a terminal once reading has taken more than a second, never when
//! stdout is not a terminal or with `--quiet`.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A byte-progress bar that stays hidden for its first second.
pub struct ReadProgress {
    bar: Option<ProgressBar>,
    start: Instant,
}

impl ReadProgress {
    /// A bar for `total` bytes; inert when `quiet` or when stdout is not a terminal.
    pub fn new(total: u64, quiet: bool) -> Self {
        let bar = (!quiet && std::io::stdout().is_terminal()).then(|| {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
            if let Ok(style) = ProgressStyle::with_template(
                "{msg} [{bar:30}] {bytes}/{total_bytes} {bytes_per_sec} eta {eta}",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar.set_message("reading");
            bar
        });
        ReadProgress {
            bar,
            start: Instant::now(),
        }
    }

    /// A bar counting `total` items (e.g. a sweep's values), labelled `what`; inert like [`Self::new`].
    pub fn counting(total: u64, quiet: bool, what: &str) -> Self {
        let p = ReadProgress::new(total, quiet);
        if let Some(bar) = &p.bar {
            if let Ok(style) =
                ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} eta {eta}")
            {
                bar.set_style(style.progress_chars("=> "));
            }
            bar.set_message(what.to_string());
        }
        p
    }

    /// Records `bytes` read so far.
    pub fn update(&self, bytes: u64) {
        if let Some(bar) = &self.bar {
            if bar.is_hidden() && self.start.elapsed() > Duration::from_secs(1) {
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
            bar.set_position(bytes);
        }
    }

    /// Counts one more item done (any thread).
    pub fn inc(&self) {
        if let Some(bar) = &self.bar {
            if bar.is_hidden() && self.start.elapsed() > Duration::from_secs(1) {
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
            bar.inc(1);
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

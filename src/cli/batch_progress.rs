//! The batch's progress display: an indicatif MultiProgress with one bar per running mission (bytes
//! read) and one overall bar (missions done). Nothing is drawn when stderr is not a terminal or with
//! `--quiet`.

use std::collections::HashMap;
use std::io::IsTerminal;
use std::sync::Mutex;

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use trajdrift::batch::run::BatchEvent;

/// Draws `BatchEvent`s; safe to call from every worker thread.
pub struct BatchBars {
    multi: Option<MultiProgress>,
    overall: Option<ProgressBar>,
    bars: Mutex<HashMap<String, ProgressBar>>,
}

impl BatchBars {
    /// Bars on stderr when it is a terminal and not `quiet`; inert otherwise.
    pub fn new(quiet: bool) -> Self {
        let multi = (!quiet && std::io::stderr().is_terminal()).then(MultiProgress::new);
        BatchBars {
            multi,
            overall: None,
            bars: Mutex::new(HashMap::new()),
        }
    }

    /// Handles one event.
    pub fn event(&self, e: BatchEvent<'_>) {
        let Some(multi) = &self.multi else { return };
        let Ok(mut bars) = self.bars.lock() else {
            return;
        };
        match e {
            BatchEvent::Planned { missions } => {
                let bar = multi.add(ProgressBar::new(missions as u64));
                if let Ok(s) = ProgressStyle::with_template(
                    "missions [{bar:30}] {pos}/{len} elapsed {elapsed} eta {eta}",
                ) {
                    bar.set_style(s.progress_chars("=> "));
                }
                bars.insert(String::new(), bar);
            }
            BatchEvent::Started { mission, bytes } => {
                let bar = multi.add(ProgressBar::new(bytes));
                if let Ok(s) = ProgressStyle::with_template(
                    "{msg:24} [{bar:30}] {bytes}/{total_bytes} {bytes_per_sec}",
                ) {
                    bar.set_style(s.progress_chars("=> "));
                }
                bar.set_message(mission.to_string());
                bars.insert(mission.to_string(), bar);
            }
            BatchEvent::Read { mission, bytes } => {
                if let Some(bar) = bars.get(mission) {
                    bar.set_position(bytes);
                }
            }
            BatchEvent::Finished { mission, .. } => {
                if let Some(bar) = bars.remove(mission) {
                    bar.finish_and_clear();
                    multi.remove(&bar);
                }
                if let Some(overall) = bars.get("").or(self.overall.as_ref()) {
                    overall.inc(1);
                }
            }
        }
    }

    /// Removes the bars.
    pub fn finish(&self) {
        if let Ok(bars) = self.bars.lock() {
            for bar in bars.values() {
                bar.finish_and_clear();
            }
        }
    }
}

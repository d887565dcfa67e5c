//! `trajdrift export`: writes any source's trajectory as TUM or CSV text (through the [`Source`] trait),
//! so evo users can take trajdrift's extraction. Written to a temporary file and renamed.

use anyhow::{anyhow, Result};

use trajdrift::report::output::OutputGuard;
use trajdrift::sources::mapped_csv::write_csv;
use trajdrift::sources::open::is_recording;
use trajdrift::sources::text::TextSource;
use trajdrift::sources::tum::write_tum;
use trajdrift::sources::{ExtractOptions, Source, StampSource};

use crate::cli::args::{text_options, ExportArgs, ExportFormatArg, StampArg};
use crate::cli::EXIT_OK;

/// Runs the command; returns the exit code.
pub fn run(a: ExportArgs) -> Result<u8> {
    // Refused before the pass, and again when written.
    OutputGuard::new(std::iter::once(a.recording.clone()).chain(a.text.kitti_times.clone()))
        .check("OUT", &a.out)?;
    let (source, topic): (Box<dyn Source>, String) = if is_recording(&a.recording) {
        let topic = a.topic.clone().ok_or_else(|| {
            anyhow!(trajdrift::Error::InvalidArgument(format!(
                "{}: give --topic TOPIC (see `trajdrift topics`)",
                a.recording.display()
            )))
        })?;
        (trajdrift::sources::open(&a.recording)?, topic)
    } else {
        let s = TextSource::open(&a.recording, text_options(&a.text)?)?;
        let topic = s.channel();
        (Box::new(s), topic)
    };
    let options = ExtractOptions {
        stamp: match a.stamp {
            StampArg::Header => StampSource::Header,
            StampArg::Log => StampSource::Log,
        },
        origin: None,
        ..ExtractOptions::default()
    };
    let extraction = source.extract(std::slice::from_ref(&topic), &options, &|_| {})?;
    let traj = &extraction
        .topics
        .first()
        .ok_or_else(|| anyhow!("{topic} was not extracted"))?
        .trajectory;
    let mut bytes = Vec::new();
    match a.format {
        ExportFormatArg::Tum => write_tum(&mut bytes, traj)?,
        ExportFormatArg::Csv => write_csv(&mut bytes, traj)?,
    }
    let guard =
        OutputGuard::new(std::iter::once(a.recording.clone()).chain(a.text.kitti_times.clone()));
    guard.write("OUT", &a.out, &bytes)?;
    for w in &extraction.warnings {
        crate::cli::warn(&w.code, &w.message);
    }
    Ok(EXIT_OK)
}

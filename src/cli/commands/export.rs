//! `trajdrift export`: writes any source's trajectory as TUM or CSV text (through the [`Source`] trait),
//! so evo users can take trajdrift's extraction. Written to a temporary file and renamed.

use anyhow::{anyhow, Result};

use trajdrift::output::OutputGuard;
use trajdrift::sources::mapped_csv::write_csv;
use trajdrift::sources::open::is_recording;
use trajdrift::sources::text::TextSource;
use trajdrift::sources::tum::write_tum;
use trajdrift::sources::{ExtractOptions, Source};

use crate::cli::args::{text_options, ExportArgs, ExportFormatArg};

/// Runs the command; returns the exit code.
pub fn run(mut a: ExportArgs) -> Result<u8> {
    if a.recording.len() < 2 {
        return Err(anyhow!(trajdrift::Error::InvalidArgument(
            "give the RECORDING (or text file) and then OUT (`-` = stdout)".into()
        )));
    }
    a.out = a.recording.pop().unwrap_or_default();
    // Refused before the pass, and again when written.
    let mut guard = OutputGuard::new(
        a.recording
            .iter()
            .cloned()
            .chain(a.text.kitti_times.clone()),
    );
    guard.claim("OUT", &a.out)?;
    let first = &a.recording[0];
    let (source, topic): (Box<dyn Source>, String) = if a.recording.len() > 1 || is_recording(first)
    {
        let topic = a.topic.clone().ok_or_else(|| {
            anyhow!(trajdrift::Error::InvalidArgument(format!(
                "{}: give --topic TOPIC (see `trajdrift topics`)",
                first.display()
            )))
        })?;
        (trajdrift::sources::open_all(&a.recording)?, topic)
    } else {
        let s = TextSource::open(first, text_options(&a.text)?)?;
        let topic = s.channel();
        (Box::new(s), topic)
    };
    let options = ExtractOptions {
        stamp: a.stamp,
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
    guard.write("OUT", &a.out, &bytes)?;
    for w in &extraction.warnings {
        crate::cli::warn(w);
    }
    Ok(crate::cli::exit_code(&extraction.warnings))
}

//! `trajdrift restamp`: a copy of the mission, as one MCAP, with every message of a clock domain moved
//! onto the reference's clock — its header stamp (each transform's of a TF batch), its log time and
//! its publish time — by its domain's model, through the one clock correction ([`crate::clock`],
//! in integer nanoseconds, as `eval` applies it). Every other message is copied with its bytes and
//! times unchanged, schemas, attachments and metadata too; the audit goes in as the attachment
//! `trajdrift-audit.json` and a metadata record `trajdrift-restamp` says which domain moved by what.
//!
//! The copy is the annotated recording's ([`crate::annotate::copy`], [`crate::annotate::any_input`]):
//! one MCAP keeps its ids and compression; bags, rosbag2 folders and missions of several files become
//! one MCAP with their messages' encodings and definitions. The input is only read; the output is
//! written by the output policy ([`crate::output::OutputFile`]: a temporary file beside it, renamed
//! when complete).
//!
//! Which stamp decides a message's shift follows the audit (`stamp`: header or log): with header
//! stamps, a stamped message moves by the correction at its header stamp and its log and publish
//! times by the same amount; a message without a header moves by the correction at its log time.
//! A piecewise clock maps a stream in order ([`ClockCorrection::stamp_in_stream`]): after a backward
//! step, the repeated stamps land after the step, not on top of the stretch before it.

use std::collections::{BTreeMap, HashMap};
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use mcap::records::MessageHeader;
use mcap::Writer;

use super::report::AuditReport;
use super::restamp_plan::{RestampPlan, Scope};
use crate::annotate::any_input::{self, CopyInput};
use crate::annotate::copy::{copy_with, Annotations, CopyOutcome, InputChannel, Rewritten};
use crate::annotate::input_info::{read_input_info, InputInfo};
use crate::annotate::stamps::{header_stamp, layout_of, map_tf_stamps, shift_stamp, StampLayout};
use crate::clock::ClockCorrection;
use crate::error::{Error, Result};
use crate::output::{OutputFile, OutputGuard};
use crate::sources::mission::{Mission, Part};
use crate::sources::recording::Recording;
use crate::sources::{Progress, StampSource};

/// The attachment holding the audit.
pub const AUDIT_ATTACHMENT: &str = "trajdrift-audit.json";
/// The metadata record saying which domain moved by what.
pub const RESTAMP_METADATA: &str = "trajdrift-restamp";

/// What a restamp wrote.
#[derive(Debug, Clone)]
pub struct RestampOutcome {
    pub path: PathBuf,
    pub copy: CopyOutcome,
    /// Messages moved, per domain name.
    pub moved: BTreeMap<String, u64>,
}

/// The per-stream state of the correction: the last landing of each (file, channel, stamp kind).
type Streams = HashMap<(usize, u16, u8), Option<i64>>;

/// The [`Annotations`] that move each domain's messages.
struct Restamper<'a> {
    output: PathBuf,
    plan: &'a RestampPlan,
    audit: &'a AuditReport,
    /// The file of each part of the mission (one entry for a single recording).
    part_files: Vec<PathBuf>,
    /// (part, channel) → its domain and stamp layout.
    routes: HashMap<(usize, u16), Option<(usize, StampLayout)>>,
    streams: Streams,
    moved: Vec<u64>,
    last_log_time: u64,
}

impl Restamper<'_> {
    fn route(&mut self, part: usize, channel: &InputChannel) -> Option<(usize, StampLayout)> {
        *self.routes.entry((part, channel.id)).or_insert_with(|| {
            let file = self.part_files.get(part).map(PathBuf::as_path);
            let d = self.plan.domain_of(file, &channel.topic)?;
            Some((d, layout_of(&channel.schema_name, &channel.schema_data)))
        })
    }
}

/// `t` moved by `dt`, or an error naming the topic.
fn moved(t: u64, dt: i64, out: &Path, topic: &str) -> Result<u64> {
    t.checked_add_signed(dt).ok_or_else(|| Error::Output {
        path: out.to_path_buf(),
        detail: format!("{topic}: time {t} ns moved by {dt} ns leaves the u64 range"),
    })
}

impl<W: Write + Seek> Annotations<W> for Restamper<'_> {
    fn start(&mut self, _: &mut Writer<W>) -> Result<()> {
        Ok(())
    }

    fn before_message(
        &mut self,
        _: &mut Writer<W>,
        _: &InputChannel,
        header: &MessageHeader,
        _: &[u8],
    ) -> Result<()> {
        self.last_log_time = self.last_log_time.max(header.log_time);
        Ok(())
    }

    fn rewrite(
        &mut self,
        part: usize,
        channel: &InputChannel,
        header: &MessageHeader,
        data: &[u8],
    ) -> Result<Option<Rewritten>> {
        let Some((d, layout)) = self.route(part, channel) else {
            return Ok(None);
        };
        let correction: &ClockCorrection = &self.plan.domains[d].correction;
        let decode_error = |detail: String| Error::Decode {
            path: self.part_files.get(part).cloned().unwrap_or_default(),
            topic: channel.topic.clone(),
            index: u64::from(header.sequence),
            detail,
        };
        let log = i64::try_from(header.log_time).unwrap_or(i64::MAX);
        let shift = |streams: &mut Streams, kind: u8, t: i64| -> Result<i64> {
            let last = streams.entry((part, channel.id, kind)).or_default();
            correction
                .stamp_in_stream(t, last)
                .map(|m| m - t)
                .ok_or_else(|| decode_error(format!("stamp {t} ns moves out of the i64 range")))
        };
        let (dt, data) = match (layout, self.audit.stamp) {
            (StampLayout::Header, StampSource::Header) => {
                let s = header_stamp(&channel.message_encoding, data).map_err(&decode_error)?;
                let dt = shift(&mut self.streams, 0, s)?;
                (
                    dt,
                    shift_stamp(&channel.message_encoding, data, dt).map_err(&decode_error)?,
                )
            }
            (StampLayout::Header, StampSource::Log) => {
                let dt = shift(&mut self.streams, 0, log)?;
                (
                    dt,
                    shift_stamp(&channel.message_encoding, data, dt).map_err(&decode_error)?,
                )
            }
            (StampLayout::TfBatch, _) => {
                let dt = shift(&mut self.streams, 1, log)?;
                let last = self.streams.entry((part, channel.id, 2)).or_default();
                let data = map_tf_stamps(&channel.message_encoding, data, &mut |t| {
                    correction.stamp_in_stream(t, last)
                })
                .map_err(&decode_error)?;
                (dt, data)
            }
            (StampLayout::None, _) => (shift(&mut self.streams, 1, log)?, data.to_vec()),
        };
        let h = MessageHeader {
            channel_id: header.channel_id,
            sequence: header.sequence,
            log_time: moved(header.log_time, dt, &self.output, &channel.topic)?,
            publish_time: moved(header.publish_time, dt, &self.output, &channel.topic)?,
        };
        self.moved[d] += 1;
        Ok(Some((h, data)))
    }

    fn finish(&mut self, w: &mut Writer<W>) -> Result<()> {
        let err = |e: mcap::McapError| Error::Output {
            path: self.output.clone(),
            detail: e.to_string(),
        };
        let mut map = BTreeMap::new();
        map.insert("tool.version".into(), env!("CARGO_PKG_VERSION").to_string());
        map.insert("reference".into(), self.audit.reference.clone());
        map.insert(
            "stamp".into(),
            format!("{:?}", self.audit.stamp).to_lowercase(),
        );
        for (d, n) in self.plan.domains.iter().zip(&self.moved) {
            let p = format!("domain.{}", d.name);
            map.insert(
                format!("{p}.scope"),
                match &d.scope {
                    Scope::File(f) => format!("file {}", f.display()),
                    Scope::Topics(t) => format!("topics {}", t.join(",")),
                },
            );
            map.insert(format!("{p}.clock_domain"), d.audit_domain.clone());
            map.insert(format!("{p}.model"), d.clock.model.as_str().into());
            map.insert(format!("{p}.offset_s"), d.clock.offset_s.to_string());
            if let Some(ppm) = d.clock.drift_ppm {
                map.insert(format!("{p}.drift_ppm"), ppm.to_string());
            }
            map.insert(format!("{p}.messages"), n.to_string());
        }
        w.write_metadata(&mcap::records::Metadata {
            name: RESTAMP_METADATA.into(),
            metadata: map,
        })
        .map_err(err)?;
        let mut json = serde_json::to_vec_pretty(self.audit).map_err(|e| Error::Output {
            path: self.output.clone(),
            detail: e.to_string(),
        })?;
        json.push(b'\n');
        w.attach(&mcap::Attachment {
            log_time: self.last_log_time,
            create_time: self.last_log_time,
            name: AUDIT_ATTACHMENT.into(),
            media_type: "application/json".into(),
            data: json.into(),
        })
        .map_err(err)
    }
}

/// Claims `out` (`--out`) against the inputs (the recordings and `others`, such as the `--audit`
/// file): not an input, not inside an input folder (a mission folder), and not an existing file
/// without `force`.
pub fn check_output(
    recordings: &[PathBuf],
    others: &[&Path],
    out: &Path,
    force: bool,
) -> Result<()> {
    let files = super::discover::expand_files(recordings)?;
    let mut guard = OutputGuard::new(recordings.iter().chain(&files));
    for p in others {
        guard.add(p);
    }
    guard.claim("--out", out)?;
    if out.exists() && !force {
        return Err(Error::InvalidArgument(format!(
            "{}: exists; pass --force to replace it",
            out.display()
        )));
    }
    Ok(())
}

/// What is copied: one MCAP (copied record by record), a mission of several files, or one recording
/// of another format.
enum Input {
    Mcap(PathBuf),
    Mission(Mission),
    One(Part),
}

impl Input {
    fn open(files: &[PathBuf]) -> Result<Input> {
        match files {
            [one] if !one.is_dir() && crate::sources::mcap::McapSource::open(one).is_ok() => {
                Ok(Input::Mcap(one.clone()))
            }
            [one] => Ok(Input::One(crate::sources::open::open_recording(one)?)),
            _ => {
                let parts = files
                    .iter()
                    .map(|p| crate::sources::open::open_recording(p))
                    .collect::<Result<Vec<Part>>>()?;
                Ok(Input::Mission(Mission::new(&files[0], parts)?))
            }
        }
    }

    /// The files as the copy names them (the plan's file scopes are compared with these).
    fn part_files(&self, files: &[PathBuf]) -> Vec<PathBuf> {
        match self {
            Input::Mission(m) => m.parts().iter().map(|p| p.path().to_path_buf()).collect(),
            _ => vec![files[0].clone()],
        }
    }

    /// The input's compression and other facts (MCAP), and the profile of the copy (others).
    fn info_and_profile(&self) -> Result<(InputInfo, String)> {
        Ok(match self {
            Input::Mcap(p) => (read_input_info(p), String::new()),
            Input::Mission(m) => (
                InputInfo::default(),
                any_input::profile(&m.channel_counts()?.0).to_string(),
            ),
            Input::One(r) => (
                InputInfo::default(),
                any_input::profile(&r.channel_counts()?.0).to_string(),
            ),
        })
    }
}

/// Writes the restamped copy of `recordings` to `out` by `plan` (made from `audit`).
pub fn restamp(
    recordings: &[PathBuf],
    audit: &AuditReport,
    plan: &RestampPlan,
    out: &Path,
    force: bool,
    progress: Progress<'_>,
) -> Result<RestampOutcome> {
    check_output(recordings, &[], out, force)?;
    let files = super::discover::expand_files(recordings)?;
    let input = Input::open(&files)?;
    let mut restamper = Restamper {
        output: out.to_path_buf(),
        plan,
        audit,
        part_files: input.part_files(&files),
        routes: HashMap::new(),
        streams: HashMap::new(),
        moved: vec![0; plan.domains.len()],
        last_log_time: 0,
    };
    let (info, profile) = input.info_and_profile()?;
    let options = mcap::WriteOptions::new()
        .compression(info.output_compression())
        .library(concat!("trajdrift ", env!("CARGO_PKG_VERSION")));
    let out_err = |e: std::io::Error| Error::Output {
        path: out.to_path_buf(),
        detail: e.to_string(),
    };
    let mut target = OutputFile::create(out)?;
    let file = std::io::BufWriter::new(target.file().try_clone().map_err(out_err)?);
    let (copy, mut sink) = match &input {
        Input::Mcap(p) => copy_with(p, file, out, options, &mut restamper, progress)?,
        Input::Mission(m) => any_input::copy_recording(
            CopyInput::Parts(m),
            file,
            out,
            options,
            &profile,
            &mut restamper,
            progress,
        )?,
        Input::One(r) => any_input::copy_recording(
            CopyInput::One(r as &dyn Recording),
            file,
            out,
            options,
            &profile,
            &mut restamper,
            progress,
        )?,
    };
    sink.flush().map_err(out_err)?;
    drop(sink);
    target.commit()?;
    let moved = plan
        .domains
        .iter()
        .zip(&restamper.moved)
        .map(|(d, n)| (d.name.clone(), *n))
        .collect();
    Ok(RestampOutcome {
        path: out.to_path_buf(),
        copy,
        moved,
    })
}

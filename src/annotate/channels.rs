//! The new channels of an annotated recording and their messages:
//!
//! - `/trajdrift/<name>/aligned`: the estimate on the reference clock. A ROS 2 stamped message (every
//!   type trajdrift reads starts with `std_msgs/Header`) is copied with only its header stamp patched
//!   in place, so everything else stays byte-identical; an estimate that is not such a message (a TUM
//!   file, TF) is written as `geometry_msgs/msg/PoseStamped` from its samples.
//! - `/trajdrift/<name>/drift_error`: one JSON message per Drift Error window, log time = window end.
//! - `/trajdrift/<name>/curvature`, `/trajdrift/reference/curvature`: the curvature signatures, JSON.
//!
//! Shifts are integer nanoseconds, added exactly to the header stamp, the log time and the publish
//! time: Δt_ns = round(applied_s × 10⁹), or per stamp the report's linear or piecewise clock model
//! ([`crate::clock`]), as Drift Error and `--export-aligned` applied it.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::io::{Seek, Write};
use std::path::PathBuf;

use mcap::records::MessageHeader;
use mcap::{McapError, Writer};
use serde::Serialize;

use super::copy::{Annotations, InputChannel};
use super::metadata::{metadata_map, ATTACHMENT_NAME, METADATA_NAME};
use crate::clock::ClockCorrection;
use crate::decode::cdr::encode_le;
use crate::decode::ros2_msgs::{Header, Point, Pose, PoseStamped, Quaternion, Time};
use crate::decode::ros2_schemas::schema_text;
use crate::error::{Error, Result};
use crate::report::json::Report;
use crate::sources::StampSource;
use crate::trajectory::Trajectory;

/// JSON schema of a drift_error message (`schemas/drift_error.schema.json`).
pub const DRIFT_ERROR_SCHEMA: &str = include_str!("../../schemas/drift_error.schema.json");
/// JSON schema of a curvature message (`schemas/curvature.schema.json`).
pub const CURVATURE_SCHEMA: &str = include_str!("../../schemas/curvature.schema.json");
const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";

/// Topic of a new channel: `/trajdrift/<name>/<what>`.
pub fn topic(name: &str, what: &str) -> String {
    format!("/trajdrift/{name}/{what}")
}

/// One Drift Error window as written on `/trajdrift/<name>/drift_error`.
#[derive(Debug, Clone, Serialize)]
pub struct DriftErrorMessage {
    pub window_m: f64,
    pub t_start: f64,
    pub t_end: f64,
    pub ref_length_m: f64,
    pub est_length_m: f64,
    pub alpha: f64,
    pub de: f64,
}

/// One curvature sample as written on the curvature channels.
#[derive(Debug, Clone, Serialize)]
pub struct CurvatureMessage {
    pub t: f64,
    pub curvature: f64,
    pub signed_curvature: f64,
    pub turn_rad: f64,
}

/// How an estimate's aligned channel is produced.
#[derive(Debug, Clone)]
pub enum AlignedSource {
    /// Patch the header stamp of every message on this input topic.
    PatchTopic(String),
    /// Write PoseStamped messages from these samples (already shifted).
    Generate(Trajectory),
}

/// What to add for one estimate.
#[derive(Debug, Clone)]
pub struct EstimatePlan {
    pub name: String,
    /// The report's clock correction of the estimate's stamps.
    pub shift: ClockCorrection,
    pub aligned: AlignedSource,
    /// The curvature signature on the reference clock: (log time ns, message).
    pub curvature: Vec<(u64, CurvatureMessage)>,
    pub drift_error: Vec<(u64, DriftErrorMessage)>,
}

/// Everything the annotated copy adds.
#[derive(Debug, Clone)]
pub struct Plan {
    pub reference_curvature: Vec<(u64, CurvatureMessage)>,
    pub estimates: Vec<EstimatePlan>,
    pub report: Report,
    /// The stamp the evaluation read (`--stamp`): the clock correction is a function of it, so a
    /// patched message's shift is taken at its header stamp or at its log time.
    pub stamp: StampSource,
}

/// A generated message waiting for its place in log-time order.
struct Pending {
    log_time: u64,
    channel: u16,
    data: Vec<u8>,
}

/// How many new messages went to each new topic.
pub type Counts = BTreeMap<String, u64>;

/// The [`Annotations`] of an evaluation: built from a [`Plan`] and the free ids of the input.
pub struct Annotator {
    output: PathBuf,
    plan: Plan,
    /// Schema ids: drift_error, curvature, PoseStamped.
    schema_ids: [u16; 3],
    /// Channel ids: reference curvature, then per estimate aligned, drift_error, curvature.
    channel_ids: Vec<u16>,
    /// Input topic → estimate index, for patched aligned channels.
    patch: HashMap<String, usize>,
    /// Estimates whose aligned channel exists already.
    aligned_added: Vec<bool>,
    pending: VecDeque<Pending>,
    sequences: HashMap<u16, u32>,
    counts: HashMap<u16, u64>,
    last_log_time: u64,
}

impl Annotator {
    /// Prepares the annotations; `free_schema_ids` (3) and `free_channel_ids` (1 + 3 per estimate) must
    /// be ids the input does not use.
    pub fn new(
        output: PathBuf,
        plan: Plan,
        free_schema_ids: &[u16],
        free_channel_ids: &[u16],
    ) -> Result<Self> {
        let need = 1 + 3 * plan.estimates.len();
        if free_schema_ids.len() < 3 || free_channel_ids.len() < need {
            return Err(Error::Output {
                path: output,
                detail: "the input uses nearly every channel or schema id; no room for the trajdrift channels".into(),
            });
        }
        let patch = plan
            .estimates
            .iter()
            .enumerate()
            .filter_map(|(i, e)| match &e.aligned {
                AlignedSource::PatchTopic(t) => Some((t.clone(), i)),
                AlignedSource::Generate(_) => None,
            })
            .collect();
        let n = plan.estimates.len();
        Ok(Annotator {
            output,
            plan,
            schema_ids: [free_schema_ids[0], free_schema_ids[1], free_schema_ids[2]],
            channel_ids: free_channel_ids[..need].to_vec(),
            patch,
            aligned_added: vec![false; n],
            pending: VecDeque::new(),
            sequences: HashMap::new(),
            counts: HashMap::new(),
            last_log_time: 0,
        })
    }

    /// Messages written per new topic.
    pub fn counts(&self) -> Counts {
        let mut out = Counts::new();
        let mut put = |id: u16, t: String| {
            out.insert(t, self.counts.get(&id).copied().unwrap_or(0));
        };
        put(self.channel_ids[0], topic("reference", "curvature"));
        for (i, e) in self.plan.estimates.iter().enumerate() {
            put(self.channel_ids[1 + 3 * i], topic(&e.name, "aligned"));
            put(self.channel_ids[2 + 3 * i], topic(&e.name, "drift_error"));
            put(self.channel_ids[3 + 3 * i], topic(&e.name, "curvature"));
        }
        out
    }

    fn err(&self, e: McapError) -> Error {
        Error::Output {
            path: self.output.clone(),
            detail: format!("{e} (an input id clashes with a trajdrift channel?)"),
        }
    }

    fn write<W: Write + Seek>(
        &mut self,
        w: &mut Writer<W>,
        channel: u16,
        log_time: u64,
        publish_time: u64,
        data: &[u8],
    ) -> Result<()> {
        let seq = self.sequences.entry(channel).or_insert(0);
        *seq = seq.wrapping_add(1);
        let header = MessageHeader {
            channel_id: channel,
            sequence: *seq,
            log_time,
            publish_time,
        };
        w.write_to_known_channel(&header, data)
            .map_err(|e| self.err(e))?;
        *self.counts.entry(channel).or_default() += 1;
        self.last_log_time = self.last_log_time.max(log_time);
        Ok(())
    }

    /// Writes pending messages up to `log_time` (all with `None`).
    fn flush<W: Write + Seek>(&mut self, w: &mut Writer<W>, log_time: Option<u64>) -> Result<()> {
        while let Some(p) = self.pending.front() {
            if log_time.is_some_and(|t| p.log_time > t) {
                break;
            }
            let Some(p) = self.pending.pop_front() else {
                break;
            };
            self.write(w, p.channel, p.log_time, p.log_time, &p.data)?;
        }
        Ok(())
    }

    fn json<T: Serialize>(&self, v: &T) -> Result<Vec<u8>> {
        serde_json::to_vec(v).map_err(|e| Error::Output {
            path: self.output.clone(),
            detail: e.to_string(),
        })
    }
}

impl<W: Write + Seek> Annotations<W> for Annotator {
    fn start(&mut self, w: &mut Writer<W>) -> Result<()> {
        let [de_schema, curv_schema, pose_schema] = self.schema_ids;
        for (id, name, text) in [
            (de_schema, "trajdrift.DriftErrorWindow", DRIFT_ERROR_SCHEMA),
            (curv_schema, "trajdrift.CurvatureSample", CURVATURE_SCHEMA),
        ] {
            w.add_schema_with_id(id, name, "jsonschema", text.as_bytes())
                .map_err(|e| self.err(e))?;
        }
        let no_meta = BTreeMap::new();
        let json_channel = |w: &mut Writer<W>, id: u16, schema: u16, t: String| {
            w.add_channel_with_id(id, schema, &t, "json", &no_meta)
        };
        json_channel(
            w,
            self.channel_ids[0],
            curv_schema,
            topic("reference", "curvature"),
        )
        .map_err(|e| self.err(e))?;
        let mut pending = Vec::new();
        for i in 0..self.plan.estimates.len() {
            let name = self.plan.estimates[i].name.clone();
            let (aligned, de, curv) = (
                self.channel_ids[1 + 3 * i],
                self.channel_ids[2 + 3 * i],
                self.channel_ids[3 + 3 * i],
            );
            json_channel(w, de, de_schema, topic(&name, "drift_error")).map_err(|e| self.err(e))?;
            json_channel(w, curv, curv_schema, topic(&name, "curvature"))
                .map_err(|e| self.err(e))?;
            let e = &self.plan.estimates[i];
            for (t, m) in &e.drift_error {
                pending.push(Pending {
                    log_time: *t,
                    channel: de,
                    data: self.json(m)?,
                });
            }
            for (t, m) in &e.curvature {
                pending.push(Pending {
                    log_time: *t,
                    channel: curv,
                    data: self.json(m)?,
                });
            }
            if let AlignedSource::Generate(traj) = &e.aligned {
                let text = schema_text(POSE_STAMPED).unwrap_or_default();
                w.add_schema_with_id(pose_schema, POSE_STAMPED, "ros2msg", text.as_bytes())
                    .map_err(|e| self.err(e))?;
                w.add_channel_with_id(
                    aligned,
                    pose_schema,
                    &topic(&name, "aligned"),
                    "cdr",
                    &no_meta,
                )
                .map_err(|e| self.err(e))?;
                self.aligned_added[i] = true;
                pending.extend(aligned_messages(traj, aligned));
            }
        }
        for (t, m) in &self.plan.reference_curvature {
            pending.push(Pending {
                log_time: *t,
                channel: self.channel_ids[0],
                data: self.json(m)?,
            });
        }
        // Stable: equal log times keep channel order, then sample order.
        pending.sort_by_key(|p| p.log_time);
        self.pending = pending.into();
        Ok(())
    }

    fn before_message(
        &mut self,
        w: &mut Writer<W>,
        channel: &InputChannel,
        header: &MessageHeader,
        data: &[u8],
    ) -> Result<()> {
        self.flush(w, Some(header.log_time))?;
        let Some(&i) = self.patch.get(&channel.topic) else {
            return Ok(());
        };
        let decode_error = |detail| Error::Decode {
            path: self.output.clone(),
            topic: channel.topic.clone(),
            index: u64::from(header.sequence),
            detail,
        };
        let stamp = match self.plan.stamp {
            StampSource::Header => {
                header_stamp(&channel.message_encoding, data).map_err(decode_error)?
            }
            StampSource::Log => i64::try_from(header.log_time).unwrap_or(i64::MAX),
        };
        // A stamp the clock model maps nowhere (repeated by a backward step) has no aligned copy.
        let Some(dt_ns) = self.plan.estimates[i].shift.stamp(stamp).map(|s| s - stamp) else {
            return Ok(());
        };
        let aligned = self.channel_ids[1 + 3 * i];
        if !self.aligned_added[i] {
            let name = self.plan.estimates[i].name.clone();
            w.add_channel_with_id(
                aligned,
                channel.schema_id,
                &topic(&name, "aligned"),
                &channel.message_encoding,
                &BTreeMap::new(),
            )
            .map_err(|e| self.err(e))?;
            self.aligned_added[i] = true;
        }
        let patched = shift_stamp(&channel.message_encoding, data, dt_ns).map_err(decode_error)?;
        let shift = |t: u64| -> Result<u64> {
            t.checked_add_signed(dt_ns).ok_or_else(|| Error::Output {
                path: self.output.clone(),
                detail: format!(
                    "{}: log time {t} shifted by {dt_ns} ns leaves the u64 range",
                    channel.topic
                ),
            })
        };
        let (log_time, publish_time) = (shift(header.log_time)?, shift(header.publish_time)?);
        self.write(w, aligned, log_time, publish_time, &patched)
    }

    fn finish(&mut self, w: &mut Writer<W>) -> Result<()> {
        self.flush(w, None)?;
        let map = metadata_map(&self.plan.report);
        w.write_metadata(&mcap::records::Metadata {
            name: METADATA_NAME.into(),
            metadata: map,
        })
        .map_err(|e| self.err(e))?;
        let mut report = self.json(&self.plan.report)?;
        report.push(b'\n');
        w.attach(&mcap::Attachment {
            log_time: self.last_log_time,
            create_time: self.last_log_time,
            name: ATTACHMENT_NAME.into(),
            media_type: "application/json".into(),
            data: report.into(),
        })
        .map_err(|e| self.err(e))?;
        Ok(())
    }
}

/// Where a stamped message keeps its header stamp: bytes 4–12, after a ROS 1 `std_msgs/Header`'s
/// `uint32 seq` (`uint32 secs, uint32 nsecs`, little endian, no encapsulation header) or after a CDR
/// encapsulation header (`int32 sec, uint32 nanosec` in the payload's byte order; plain CDR only).
#[derive(Debug, Clone, Copy, PartialEq)]
enum StampLayout {
    Ros1,
    Cdr { little: bool },
}

impl StampLayout {
    /// The layout of `data` in `encoding`, checked against its length and encapsulation.
    fn of(encoding: &str, data: &[u8]) -> std::result::Result<Self, String> {
        let too_short = |what: &str| Err(format!("{} bytes, too short for {what}", data.len()));
        match encoding {
            "ros1" if data.len() < 12 => too_short("a stamped ROS 1 message"),
            "ros1" => Ok(StampLayout::Ros1),
            "cdr" if data.len() < 12 => too_short("a stamped message"),
            "cdr" => match (data[0], data[1]) {
                (0, 1) => Ok(StampLayout::Cdr { little: true }),
                (0, 0) => Ok(StampLayout::Cdr { little: false }),
                (a, b) => Err(format!("encapsulation 0x{a:02x}{b:02x} is not plain CDR")),
            },
            other => Err(format!(
                "message encoding `{other}`: trajdrift patches stamps of `cdr` and `ros1` messages only"
            )),
        }
    }

    fn read(self, data: &[u8]) -> i64 {
        let word = |at: usize| [data[at], data[at + 1], data[at + 2], data[at + 3]];
        let (sec, nanosec) = match self {
            StampLayout::Ros1 => (
                i64::from(u32::from_le_bytes(word(4))),
                u32::from_le_bytes(word(8)),
            ),
            StampLayout::Cdr { little: true } => (
                i64::from(i32::from_le_bytes(word(4))),
                u32::from_le_bytes(word(8)),
            ),
            StampLayout::Cdr { little: false } => (
                i64::from(i32::from_be_bytes(word(4))),
                u32::from_be_bytes(word(8)),
            ),
        };
        sec * 1_000_000_000 + i64::from(nanosec)
    }

    /// `data` with the stamp `ns` written in, in a copy.
    fn write(self, data: &[u8], ns: i64) -> std::result::Result<Vec<u8>, String> {
        let (sec, nanosec) = (
            ns.div_euclid(1_000_000_000),
            ns.rem_euclid(1_000_000_000) as u32,
        );
        let sec: [u8; 4] = match self {
            StampLayout::Ros1 => u32::try_from(sec)
                .map_err(|_| format!("stamp {ns} ns shifted out of the uint32 seconds range"))?
                .to_le_bytes(),
            StampLayout::Cdr { little } => {
                let s = i32::try_from(sec)
                    .map_err(|_| format!("stamp {ns} ns shifted out of the int32 seconds range"))?;
                if little {
                    s.to_le_bytes()
                } else {
                    s.to_be_bytes()
                }
            }
        };
        let nanosec = match self {
            StampLayout::Cdr { little: false } => nanosec.to_be_bytes(),
            _ => nanosec.to_le_bytes(),
        };
        let mut out = data.to_vec();
        out[4..8].copy_from_slice(&sec);
        out[8..12].copy_from_slice(&nanosec);
        Ok(out)
    }
}

/// The header stamp (ns) of a stamped message in its own encoding: `cdr` (ROS 2) or `ros1`.
pub fn header_stamp(encoding: &str, data: &[u8]) -> std::result::Result<i64, String> {
    Ok(StampLayout::of(encoding, data)?.read(data))
}

/// Shifts the header stamp of a stamped message by `dt_ns` in its own encoding, in a copy: everything
/// else stays byte-identical.
pub fn shift_stamp(
    encoding: &str,
    data: &[u8],
    dt_ns: i64,
) -> std::result::Result<Vec<u8>, String> {
    let layout = StampLayout::of(encoding, data)?;
    layout.write(data, layout.read(data) + dt_ns)
}

/// The aligned estimate as `PoseStamped` messages on `channel`, one per pose (log time = its
/// stamp; poses before 1970 have no log time and are left out).
fn aligned_messages(traj: &Trajectory, channel: u16) -> Vec<Pending> {
    let mut out = Vec::with_capacity(traj.stamps_ns.len());
    for (k, &stamp) in traj.stamps_ns.iter().enumerate() {
        let Ok(log_time) = u64::try_from(stamp) else {
            continue;
        };
        let p = traj.positions[k];
        let q = traj
            .orientations
            .as_ref()
            .and_then(|o| o.get(k))
            .map(|q| Quaternion {
                x: q.i,
                y: q.j,
                z: q.k,
                w: q.w,
            })
            .unwrap_or_default();
        let msg = PoseStamped {
            header: Header {
                stamp: Time::from_ns(stamp),
                frame_id: String::new(),
            },
            pose: Pose {
                position: Point {
                    x: p.x,
                    y: p.y,
                    z: p.z,
                },
                orientation: q,
            },
        };
        out.push(Pending {
            log_time,
            channel,
            data: encode_le(&msg),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn shift_moves_only_the_stamp(sec in 0i32..2_000_000_000, ns in 0u32..1_000_000_000,
                                      dt in -10_000_000_000i64..10_000_000_000, little: bool,
                                      tail in proptest::collection::vec(any::<u8>(), 0..40)) {
            let mut data = vec![0u8, u8::from(little), 0, 0];
            if little {
                data.extend(sec.to_le_bytes());
                data.extend(ns.to_le_bytes());
            } else {
                data.extend(sec.to_be_bytes());
                data.extend(ns.to_be_bytes());
            }
            data.extend(&tail);
            let out = shift_stamp("cdr", &data, dt).unwrap();
            prop_assert_eq!(&out[12..], &data[12..]);
            prop_assert_eq!(&out[..4], &data[..4]);
            let f = |b: &[u8]| { let mut a = [0u8; 4]; a.copy_from_slice(b); a };
            let (s2, n2) = if little {
                (i32::from_le_bytes(f(&out[4..8])), u32::from_le_bytes(f(&out[8..12])))
            } else {
                (i32::from_be_bytes(f(&out[4..8])), u32::from_be_bytes(f(&out[8..12])))
            };
            prop_assert!(n2 < 1_000_000_000);
            prop_assert_eq!(s2 as i64 * 1_000_000_000 + n2 as i64, sec as i64 * 1_000_000_000 + ns as i64 + dt);
            prop_assert_eq!(header_stamp("cdr", &data).unwrap(), sec as i64 * 1_000_000_000 + ns as i64);
            prop_assert_eq!(header_stamp("cdr", &out).unwrap(), sec as i64 * 1_000_000_000 + ns as i64 + dt);
        }
    }

    #[test]
    fn ros1_shift_carries_into_seconds() {
        let mut data = vec![7, 0, 0, 0];
        data.extend_from_slice(&10u32.to_le_bytes());
        data.extend_from_slice(&900_000_000u32.to_le_bytes());
        data.extend_from_slice(&[0, 0, 0, 0, 42]);
        let out = shift_stamp("ros1", &data, 200_000_001).unwrap();
        assert_eq!(&out[..4], &data[..4]);
        assert_eq!(out[4..8], 11u32.to_le_bytes());
        assert_eq!(out[8..12], 100_000_001u32.to_le_bytes());
        assert_eq!(&out[12..], &data[12..]);
        assert_eq!(header_stamp("ros1", &out).unwrap(), 11_100_000_001);
        let back = shift_stamp("ros1", &out, -200_000_001).unwrap();
        assert_eq!(back, data);
        assert!(shift_stamp("ros1", &data, -11_000_000_000).is_err());
        assert!(shift_stamp("json", &data, 1).is_err());
    }

    #[test]
    fn rejects_short_and_non_cdr() {
        assert!(shift_stamp("cdr", &[0, 1, 0, 0], 1).is_err());
        assert!(shift_stamp("cdr", &[0, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0], 1).is_err());
    }
}

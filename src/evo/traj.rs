//! `trajdrift traj`: evo_traj's inspection, checks, conversions, alignment and figures.
//!
//! Trajectories are read by trajdrift's readers (text files of any supported format, topics and TF
//! chains of recordings), which sort rows by stamp and drop repeated stamps, counting both
//! ([`RowAudit`]). The checks are evo_traj's `--full_check` (`PosePath3D.check`,
//! `PoseTrajectory3D.check`): rotation matrices in SE(3) (KITTI rows: det ≈ 1 and RᵀR ≈ I within
//! evo's 1e-6), unit quaternions (norm within numpy's `allclose` of 1: 1e-8 + 1e-5), stamps
//! ascending and unique; the quaternion norms and matrices are taken from the file as written (the
//! readers normalise them), and each check says how many rows fail it.

use std::collections::BTreeMap;
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, NamedInput};
use crate::metrics::standard::associate::associate;
use crate::metrics::standard::umeyama::{self, Similarity};
use crate::metrics::standard::{Poses, StampSeconds, SyncMethod};
use crate::output::{OutputFile, OutputGuard};
use crate::plot::evo::{EvoFigure, PlotMode, TrajectoryMap, XyzOverTime};
use crate::sources::text::{read_text_audited, TextFormat, TextOptions};
use crate::sources::Warning;
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

/// One trajectory of the command line.
#[derive(Debug, Clone)]
pub struct TrajInput {
    /// evo's compact name: the file stem, or the topic.
    pub name: String,
    /// The file it came from.
    pub path: PathBuf,
    pub trajectory: Trajectory,
    /// KITTI pose files have no stamps (paired by index).
    pub stamped: bool,
    pub rows: RowAudit,
    pub checks: RawChecks,
}

/// What the file held as written.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RawChecks {
    /// Rows whose quaternion norm is not 1 (within numpy's allclose), `None` when not checked
    /// (no orientation in the source, or a recording whose messages were read normalised).
    pub non_unit_quaternions: Option<u64>,
    /// The largest |‖q‖ − 1|.
    pub worst_norm_deviation: f64,
    /// Rows whose rotation matrix is not in SO(3) (KITTI), `None` when not checked.
    pub not_se3: Option<u64>,
}

/// Reads a text trajectory (`format` forced by evo's form word, else detected).
pub fn load_text(path: &Path, format: Option<TextFormat>) -> Result<TrajInput> {
    let options = TextOptions {
        format,
        ..TextOptions::default()
    };
    let (trajectory, format, rows) = read_text_audited(path, &options)?;
    let checks = raw_checks(path, format)?;
    Ok(TrajInput {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        path: path.to_path_buf(),
        trajectory,
        stamped: format != TextFormat::Kitti,
        rows,
        checks,
    })
}

/// Reads `topics` (topics or `/tf:PARENT:CHILD` chains) of a recording; with what the read warns of
/// (a recording cut short, [`crate::eval::inputs::Inputs::warnings`]).
pub fn load_topics(recording: &Path, topics: &[String]) -> Result<(Vec<TrajInput>, Vec<Warning>)> {
    let Some((first, rest)) = topics.split_first() else {
        return Ok((Vec::new(), Vec::new()));
    };
    let config = EvalConfig::new(
        Some(recording.to_path_buf()),
        NamedInput::topic(first),
        rest.iter().map(|t| NamedInput::topic(t)).collect(),
    );
    let inputs = crate::eval::inputs::load(&config, &|_| {})?;
    let loaded = std::iter::once(inputs.reference)
        .chain(inputs.estimates)
        .zip(topics)
        .map(|(l, topic)| TrajInput {
            name: topic.clone(),
            path: recording.to_path_buf(),
            trajectory: l.trajectory,
            stamped: true,
            rows: l.rows,
            checks: RawChecks::default(),
        })
        .collect();
    Ok((loaded, inputs.warnings))
}

/// numpy's `allclose(norm, 1)`.
fn unit(norm: f64) -> bool {
    (norm - 1.0).abs() <= 1e-8 + 1e-5
}

/// The quaternion norms and rotation matrices as written in the file.
fn raw_checks(path: &Path, format: TextFormat) -> Result<RawChecks> {
    let io = |cause| Error::Io {
        path: path.to_path_buf(),
        cause,
    };
    let mut c = RawChecks::default();
    match format {
        TextFormat::Tum => {
            let file = std::fs::File::open(path).map_err(io)?;
            let (mut bad, mut seen) = (0u64, false);
            for line in std::io::BufReader::new(file).lines() {
                let line = line.map_err(io)?;
                let f: Vec<f64> = line
                    .split(|ch: char| ch.is_whitespace() || ch == ',')
                    .filter(|s| !s.is_empty())
                    .map_while(|s| s.parse::<f64>().ok())
                    .collect();
                if line.trim_start().starts_with('#') || f.len() != 8 {
                    continue;
                }
                seen = true;
                let n = (f[4] * f[4] + f[5] * f[5] + f[6] * f[6] + f[7] * f[7]).sqrt();
                c.worst_norm_deviation = c.worst_norm_deviation.max((n - 1.0).abs());
                if !unit(n) {
                    bad += 1;
                }
            }
            c.non_unit_quaternions = seen.then_some(bad);
        }
        TextFormat::Euroc => {
            let mut r = csv::ReaderBuilder::new()
                .has_headers(true)
                .trim(csv::Trim::All)
                .flexible(true)
                .from_path(path)
                .map_err(|e| Error::Metric(format!("{}: {e}", path.display())))?;
            let mut bad = 0u64;
            for rec in r.records().flatten() {
                let q: Vec<f64> = (4..8)
                    .filter_map(|k| rec.get(k).and_then(|s| s.parse().ok()))
                    .collect();
                if q.len() == 4 {
                    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
                    c.worst_norm_deviation = c.worst_norm_deviation.max((n - 1.0).abs());
                    if !unit(n) {
                        bad += 1;
                    }
                }
            }
            c.non_unit_quaternions = Some(bad);
        }
        TextFormat::Kitti => {
            let rows = crate::sources::kitti::read_kitti_matrices(path)?;
            let bad = rows
                .iter()
                .filter(|(r, _)| {
                    let det_ok = (r.determinant() - 1.0).abs() <= 1e-6 + 1e-5;
                    let g = r.transpose() * r;
                    let inv_ok = (0..3).all(|i| {
                        (0..3).all(|j| {
                            let e = if i == j { 1.0 } else { 0.0 };
                            (g[(i, j)] - e).abs() <= 1e-6 + 1e-5 * f64::abs(e)
                        })
                    });
                    !(det_ok && inv_ok)
                })
                .count() as u64;
            c.not_se3 = Some(bad);
        }
        TextFormat::Csv => {}
    }
    Ok(c)
}

/// evo's infos and statistics of one trajectory, and our gap count.
#[derive(Debug, Clone, Default)]
pub struct Info {
    pub poses: usize,
    pub length_m: f64,
    pub duration_s: Option<f64>,
    pub rate_hz: Option<f64>,
    pub dt_max_s: Option<f64>,
    /// Steps longer than twice the median step.
    pub gaps: usize,
    pub t_start_s: Option<f64>,
    pub t_end_s: Option<f64>,
    pub speed_mean_mps: Option<f64>,
    pub speed_max_mps: Option<f64>,
}

/// The information of `t`.
pub fn info(t: &TrajInput) -> Info {
    let tr = &t.trajectory;
    let length_m = tr.positions.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let mut i = Info {
        poses: tr.len(),
        length_m,
        ..Info::default()
    };
    if !t.stamped || tr.len() < 2 {
        return i;
    }
    let secs: Vec<f64> = tr
        .stamps_ns
        .iter()
        .map(|&s| StampSeconds::Decimal.convert(s))
        .collect();
    let dts: Vec<f64> = secs.windows(2).map(|w| w[1] - w[0]).collect();
    let mut sorted = dts.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let duration = secs[secs.len() - 1] - secs[0];
    let speeds: Vec<f64> = tr
        .positions
        .windows(2)
        .zip(&dts)
        .filter(|(_, &dt)| dt > 0.0)
        .map(|(w, dt)| (w[1] - w[0]).norm() / dt)
        .collect();
    i.duration_s = Some(duration);
    i.rate_hz = (duration > 0.0).then(|| (tr.len() - 1) as f64 / duration);
    i.dt_max_s = sorted.last().copied();
    i.gaps = dts.iter().filter(|&&d| d > 2.0 * median).count();
    i.t_start_s = Some(secs[0]);
    i.t_end_s = secs.last().copied();
    i.speed_mean_mps =
        (!speeds.is_empty()).then(|| speeds.iter().sum::<f64>() / speeds.len() as f64);
    i.speed_max_mps = speeds.iter().copied().reduce(f64::max);
    i
}

/// The information table: one row per trajectory.
pub fn info_table(ts: &[&TrajInput]) -> String {
    let head = [
        "name",
        "poses",
        "length (m)",
        "duration (s)",
        "rate (Hz)",
        "dt_max (s)",
        "gaps",
        "going back",
        "duplicates",
    ];
    let opt = |v: Option<f64>, d: usize| v.map_or("–".to_string(), |x| format!("{x:.d$}"));
    let mut rows: Vec<Vec<String>> = vec![head.iter().map(|s| s.to_string()).collect()];
    for t in ts {
        let i = info(t);
        rows.push(vec![
            t.name.clone(),
            i.poses.to_string(),
            format!("{:.3}", i.length_m),
            opt(i.duration_s, 3),
            opt(i.rate_hz, 2),
            opt(i.dt_max_s, 4),
            if t.stamped {
                i.gaps.to_string()
            } else {
                "–".into()
            },
            t.rows.stamp_going_back.to_string(),
            t.rows.duplicate_stamp.to_string(),
        ]);
    }
    let cols = rows[0].len();
    let w: Vec<usize> = (0..cols)
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    rows.iter()
        .map(|r| {
            r.iter()
                .enumerate()
                .map(|(c, s)| {
                    if c == 0 {
                        format!("{s:<width$}", width = w[c])
                    } else {
                        format!("{s:>width$}", width = w[c])
                    }
                })
                .collect::<Vec<_>>()
                .join("  ")
                + "\n"
        })
        .collect()
}

/// The outcome of evo's checks on one trajectory, in evo's words, with counts.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckOutcome {
    pub se3_conform: Option<bool>,
    pub quaternions_ok: Option<bool>,
    pub timestamps_ok: Option<bool>,
    pub lines: Vec<(String, String)>,
}

impl CheckOutcome {
    /// Whether every check that ran passed.
    pub fn valid(&self) -> bool {
        [self.se3_conform, self.quaternions_ok, self.timestamps_ok]
            .iter()
            .all(|c| c.unwrap_or(true))
    }
}

/// evo's `check()` of `t`.
pub fn check(t: &TrajInput) -> CheckOutcome {
    let c = &t.checks;
    let mut lines = vec![("array shapes".to_string(), "ok".to_string())];
    let se3 = c.not_se3.map(|n| n == 0);
    lines.push((
        "SE(3) conform".into(),
        match c.not_se3 {
            None | Some(0) => "yes".into(),
            Some(n) => format!("no (poses are not valid SE(3) matrices: {n} rows)"),
        },
    ));
    let quats = c.non_unit_quaternions.map(|n| n == 0);
    lines.push((
        "quaternions".into(),
        match c.non_unit_quaternions {
            Some(0) => "ok".into(),
            Some(n) => format!(
                "invalid (must be unit quaternions: {n} of {} rows, largest |norm − 1| {:.2e})",
                t.rows.read, c.worst_norm_deviation
            ),
            None => "ok (read normalised; not checked in the source)".into(),
        },
    ));
    let mut stamps = None;
    if t.stamped {
        lines.push(("nr. of stamps".into(), "ok".into()));
        let (back, dup) = (t.rows.stamp_going_back, t.rows.duplicate_stamp);
        stamps = Some(back == 0 && dup == 0);
        lines.push((
            "timestamps".into(),
            if back == 0 && dup == 0 {
                "ok".into()
            } else {
                format!(
                    "wrong, not ascending or duplicates: {back} going back, {dup} duplicate (trajdrift sorts and keeps the first of each stamp)"
                )
            },
        ));
    }
    lines.sort();
    CheckOutcome {
        se3_conform: se3,
        quaternions_ok: quats,
        timestamps_ok: stamps,
        lines,
    }
}

/// evo_traj's per-trajectory block (`--full_check` / `-v`): infos, checks, statistics.
pub fn full_check_text(t: &TrajInput) -> String {
    let i = info(t);
    let tr = &t.trajectory;
    let sep = "-".repeat(80);
    let mut s = format!("{sep}\nname:\t{}\ninfos:\n", t.name);
    let mut infos: BTreeMap<&str, String> = BTreeMap::new();
    infos.insert("nr. of poses", i.poses.to_string());
    infos.insert("path length (m)", format!("{}", i.length_m));
    let pos = |p: Option<&Vector3<f64>>| {
        p.map_or(String::new(), |p| format!("[{} {} {}]", p.x, p.y, p.z))
    };
    infos.insert("pos_start (m)", pos(tr.positions.first()));
    infos.insert("pos_end (m)", pos(tr.positions.last()));
    if let (Some(d), Some(a), Some(b)) = (i.duration_s, i.t_start_s, i.t_end_s) {
        infos.insert("duration (s)", format!("{d}"));
        infos.insert("t_start (s)", format!("{a}"));
        infos.insert("t_end (s)", format!("{b}"));
    }
    for (k, v) in infos {
        s += &format!("\t{k}\t{v}\n");
    }
    s += "checks:\n";
    for (k, v) in check(t).lines {
        s += &format!("\t{k}\t{v}\n");
    }
    if let Some(d) = t.rows.describe() {
        s += &format!("rows:\t{d}\n");
    }
    s += "stats:\n";
    if let (Some(vm), Some(vx)) = (i.speed_mean_mps, i.speed_max_mps) {
        s += &format!("\tdt_max (s)\t{:.6}\n", i.dt_max_s.unwrap_or(0.0));
        s += &format!("\tgaps (steps > 2× the median)\t{}\n", i.gaps);
        s += &format!("\tv_avg (m/s)\t{vm:.6}\n\tv_max (m/s)\t{vx:.6}\n");
    }
    s
}

/// Alignment of the trajectories onto the reference (`--ref` with `-a`, `-s`, `--align_origin`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AlignOptions {
    pub align: bool,
    pub correct_scale: bool,
    pub align_origin: bool,
    pub n_to_align: Option<usize>,
    pub t_max_diff_s: f64,
    /// Keep only the poses associated with the reference (`--sync`).
    pub sync: bool,
    pub interpolate: bool,
}

fn poses_of(t: &TrajInput) -> Poses {
    Poses::from_trajectory(
        t.trajectory.clone(),
        t.stamped.then_some(StampSeconds::Decimal),
    )
}

/// Associates `t` with `reference` (or pairs by index when either has no stamps), aligns it as
/// asked, and returns it transformed (whole, or the associated poses with `sync`) with the
/// similarity applied.
pub fn align_to(
    reference: &TrajInput,
    t: &TrajInput,
    o: &AlignOptions,
) -> Result<(Trajectory, Similarity)> {
    let (r, e) = if reference.stamped && t.stamped {
        associate(
            poses_of(reference),
            poses_of(t),
            o.t_max_diff_s,
            0.0,
            if o.interpolate {
                SyncMethod::Interpolation
            } else {
                SyncMethod::NearestTime
            },
        )?
    } else {
        if reference.trajectory.len() != t.trajectory.len() {
            return Err(Error::Metric(format!(
                "{} and the reference {} have {} and {} poses: paths without stamps are paired by index",
                t.name,
                reference.name,
                t.trajectory.len(),
                reference.trajectory.len()
            )));
        }
        (poses_of(reference), poses_of(t))
    };
    let n = o.n_to_align.map_or(e.len(), |n| n.min(e.len()));
    let (x, y) = (&e.positions[..n], &r.positions[..n]);
    let sim = if o.align_origin {
        umeyama::origin(&r, &e)?
    } else if o.align || o.correct_scale {
        let s = umeyama::umeyama(x, y, o.correct_scale)?;
        if o.align {
            s
        } else {
            Similarity {
                rotation: nalgebra::Matrix3::identity(),
                translation: Vector3::zeros(),
                scale: s.scale,
            }
        }
    } else {
        Similarity::identity()
    };
    let mut out = if o.sync {
        let stamps: Vec<i64> = match &e.stamps_s {
            Some(s) => s.iter().map(|&t| (t * 1e9).round() as i64).collect(),
            None => t.trajectory.stamps_ns[..e.len()].to_vec(),
        };
        Trajectory {
            stamps_ns: stamps,
            positions: e.positions.clone(),
            orientations: e.rotations.as_ref().map(|_| {
                (0..e.len())
                    .map(|i| {
                        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(
                            &e.rotation(i),
                        ))
                    })
                    .collect()
            }),
        }
    } else {
        t.trajectory.clone()
    };
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&sim.rotation));
    for p in &mut out.positions {
        *p = sim.rotation * (*p * sim.scale) + sim.translation;
    }
    if let Some(o) = out.orientations.as_mut() {
        for x in o.iter_mut() {
            *x = q * *x;
        }
    }
    Ok((out, sim))
}

/// Adds `offset_s` to every stamp of `t` (evo_traj's `--t_offset`).
pub fn shift(t: &mut Trajectory, offset_s: f64) {
    let ns = (offset_s * 1e9).round() as i64;
    for s in &mut t.stamps_ns {
        *s += ns;
    }
}

/// Output file formats of the conversions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SaveAs {
    Tum,
    Kitti,
}

/// Writes `t` as TUM or KITTI to `path` (guarded, temporary file + rename).
pub fn save(
    guard: &OutputGuard,
    flag: &str,
    path: &Path,
    t: &Trajectory,
    as_: SaveAs,
) -> Result<()> {
    guard.check(flag, path)?;
    let mut f = OutputFile::create(path)?;
    let err = |e: std::io::Error| Error::Output {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    {
        let mut w = std::io::BufWriter::new(f.file());
        match as_ {
            SaveAs::Tum => crate::sources::tum::write_tum(&mut w, t).map_err(err)?,
            SaveAs::Kitti => {
                for i in 0..t.len() {
                    let r = t
                        .orientations
                        .as_ref()
                        .map_or_else(nalgebra::Matrix3::identity, |o| {
                            *o[i].to_rotation_matrix().matrix()
                        });
                    let p = t.positions[i];
                    let v = [
                        r[(0, 0)],
                        r[(0, 1)],
                        r[(0, 2)],
                        p.x,
                        r[(1, 0)],
                        r[(1, 1)],
                        r[(1, 2)],
                        p.y,
                        r[(2, 0)],
                        r[(2, 1)],
                        r[(2, 2)],
                        p.z,
                    ];
                    let line: Vec<String> = v.iter().map(|x| format!("{x:e}")).collect();
                    writeln!(w, "{}", line.join(" ")).map_err(err)?;
                }
            }
        }
        w.flush().map_err(err)?;
    }
    f.commit()
}

/// Writes every trajectory as `geometry_msgs/msg/PoseStamped` (CDR) on its own topic to one MCAP
/// (log time = header stamp), the ROS 2 recording evo writes as a rosbag2 folder or ROS 1 bag.
pub fn save_mcap(
    guard: &OutputGuard,
    flag: &str,
    path: &Path,
    ts: &[(String, &Trajectory)],
) -> Result<()> {
    use crate::decode::ros2_msgs::{Header, Point, Pose, PoseStamped, Quaternion, Time};
    guard.check(flag, path)?;
    let mcap_err = |e: mcap::McapError| Error::Output {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    let mut f = OutputFile::create(path)?;
    {
        let file = f.file().try_clone().map_err(|e| Error::Output {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })?;
        let mut w = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("trajdrift ", env!("CARGO_PKG_VERSION")))
            .create(std::io::BufWriter::new(file))
            .map_err(mcap_err)?;
        let ty = "geometry_msgs/msg/PoseStamped";
        let text = crate::decode::ros2_schemas::schema_text(ty).unwrap_or_default();
        let schema = w
            .add_schema(ty, "ros2msg", text.as_bytes())
            .map_err(mcap_err)?;
        for (topic, t) in ts {
            let ch = w
                .add_channel(schema, topic, "cdr", &BTreeMap::new())
                .map_err(mcap_err)?;
            for i in 0..t.len() {
                let q = t
                    .orientations
                    .as_ref()
                    .map_or_else(UnitQuaternion::identity, |o| o[i]);
                let p = t.positions[i];
                let msg = PoseStamped {
                    header: Header {
                        stamp: Time::from_ns(t.stamps_ns[i]),
                        frame_id: "world".into(),
                    },
                    pose: Pose {
                        position: Point {
                            x: p.x,
                            y: p.y,
                            z: p.z,
                        },
                        orientation: Quaternion {
                            x: q.i,
                            y: q.j,
                            z: q.k,
                            w: q.w,
                        },
                    },
                };
                let stamp = u64::try_from(t.stamps_ns[i]).unwrap_or(0);
                let header = mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: i as u32,
                    log_time: stamp,
                    publish_time: stamp,
                };
                w.write_to_known_channel(&header, &crate::decode::cdr::encode_le(&msg))
                    .map_err(mcap_err)?;
            }
        }
        w.finish().map_err(mcap_err)?;
    }
    f.commit()
}

/// A topic name for a trajectory (evo's `to_topic_name`): `/` + the name with spaces as `_`.
pub fn topic_name(name: &str) -> String {
    if name.starts_with('/') {
        name.to_string()
    } else {
        format!("/{}", name.replace([' ', ':'], "_"))
    }
}

/// evo_traj's figures: the trajectories in the plot mode's plane (or 3-D) and x/y/z over time.
pub fn figures(
    ts: &[(String, &Trajectory)],
    reference: Option<(&str, &Trajectory)>,
    mode: PlotMode,
    relative_time: bool,
) -> Vec<(String, EvoFigure)> {
    let pts = |t: &Trajectory| {
        t.positions
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect::<Vec<_>>()
    };
    let t0 = reference
        .map(|r| r.1)
        .into_iter()
        .chain(ts.iter().map(|t| t.1))
        .filter_map(|t| t.stamps_ns.first().copied())
        .min()
        .unwrap_or(0);
    let secs = |t: &Trajectory| {
        t.stamps_ns
            .iter()
            .zip(&t.positions)
            .map(|(&s, p)| {
                let s = if relative_time { s - t0 } else { s };
                (StampSeconds::Decimal.convert(s), [p.x, p.y, p.z])
            })
            .collect::<Vec<_>>()
    };
    let mut xyz: Vec<crate::plot::evo::TimedTrajectory> = Vec::new();
    if let Some((n, r)) = reference {
        xyz.push((format!("{n} (reference)"), secs(r)));
    }
    xyz.extend(ts.iter().map(|(n, t)| (n.clone(), secs(t))));
    vec![
        (
            "trajectories".into(),
            EvoFigure::Map(TrajectoryMap {
                title: "trajectories".into(),
                mode,
                reference: reference.map(|r| pts(r.1)),
                trajectories: ts.iter().map(|(n, t)| (n.clone(), pts(t))).collect(),
                coloured: None,
            }),
        ),
        (
            "xyz".into(),
            EvoFigure::Xyz(XyzOverTime {
                title: "x, y, z".into(),
                x_label: if relative_time {
                    "t (s from the start)"
                } else {
                    "t (s)"
                }
                .into(),
                trajectories: xyz,
            }),
        ),
    ]
}

/// Reads evo_traj's `--transform_left/--transform_right FILE`: a JSON object `{x, y, z, qx, qy, qz,
/// qw[, scale]}`, a `.npy` 4×4 matrix, or a text file of a 4×4 matrix (`np.savetxt`); refused unless
/// it is a Sim(3) (rotation times a positive scale, last row 0 0 0 1), as evo refuses it.
pub fn load_transform(path: &Path) -> Result<Similarity> {
    let bytes = std::fs::read(path).map_err(|cause| Error::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    let bad = |why: String| {
        Error::InvalidArgument(format!(
            "{}: {why}; expected a JSON {{\"x\", \"y\", \"z\", \"qx\", \"qy\", \"qz\", \"qw\"[, \"scale\"]}}, a .npy or a text 4x4 Sim(3) matrix",
            path.display()
        ))
    };
    let text = String::from_utf8_lossy(&bytes);
    if text.trim_start().starts_with('{') {
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| bad(format!("not JSON ({e})")))?;
        let f = |k: &str| v.get(k).and_then(|x| x.as_f64());
        let (Some(x), Some(y), Some(z), Some(qx), Some(qy), Some(qz), Some(qw)) =
            (f("x"), f("y"), f("z"), f("qx"), f("qy"), f("qz"), f("qw"))
        else {
            return Err(bad("a key is missing".into()));
        };
        let q = nalgebra::Quaternion::new(qw, qx, qy, qz);
        // A zero or non-finite quaternion has no rotation (normalising it never ends or gives NaN).
        if !(q.norm().is_finite() && q.norm() > 1e-9) {
            return Err(bad(format!(
                "the quaternion ({qx}, {qy}, {qz}, {qw}) has no rotation (norm {})",
                q.norm()
            )));
        }
        let q = UnitQuaternion::from_quaternion(q);
        return finite_similarity(
            Similarity {
                rotation: *q.to_rotation_matrix().matrix(),
                translation: Vector3::new(x, y, z),
                scale: f("scale").unwrap_or(1.0),
            },
            bad,
        );
    }
    let m: Vec<f64> = if bytes.starts_with(b"\x93NUMPY") {
        let a = crate::report::npy::read_npy(&bytes).map_err(bad)?;
        if a.shape != [4, 4] {
            return Err(bad(format!("shape {:?}", a.shape)));
        }
        a.data
    } else {
        text.split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .map(|s| {
                s.parse::<f64>()
                    .map_err(|_| bad(format!("{s:?} is not a number")))
            })
            .collect::<Result<Vec<_>>>()?
    };
    if m.len() != 16 {
        return Err(bad(format!("{} numbers", m.len())));
    }
    if m.iter().any(|v| !v.is_finite()) {
        return Err(bad("a number is not finite".into()));
    }
    let sr = nalgebra::Matrix3::from_fn(|i, j| m[4 * i + j]);
    let det = sr.determinant();
    if det <= 0.0 || m[12..] != [0.0, 0.0, 0.0, 1.0] {
        return Err(bad("not a Sim(3) matrix".into()));
    }
    let scale = det.cbrt();
    let rotation = sr / scale;
    let g = rotation.transpose() * rotation;
    if (g - nalgebra::Matrix3::identity()).abs().max() > 1e-6 {
        return Err(bad("not a Sim(3) matrix (rotation not orthonormal)".into()));
    }
    finite_similarity(
        Similarity {
            rotation,
            translation: Vector3::new(m[3], m[7], m[11]),
            scale,
        },
        bad,
    )
}

/// `s`, unless a number of it is not finite or its scale is not positive (its inverse, and every
/// pose it moves, would be NaN): `bad` says why.
fn finite_similarity(s: Similarity, bad: impl Fn(String) -> Error) -> Result<Similarity> {
    let finite = s
        .rotation
        .iter()
        .chain(s.translation.iter())
        .all(|v| v.is_finite());
    if !finite {
        return Err(bad("a number is not finite".into()));
    }
    if !(s.scale.is_finite() && s.scale > 0.0) {
        return Err(bad(format!("scale {} is not a number above zero", s.scale)));
    }
    Ok(s)
}

/// The inverse of a similarity (`--invert_transform`).
pub fn invert(s: &Similarity) -> Similarity {
    let rt = s.rotation.transpose();
    Similarity {
        rotation: rt,
        translation: -(rt * s.translation) / s.scale,
        scale: 1.0 / s.scale,
    }
}

/// evo's `transform`: `T·P_i` (left), `P_i·T` (right), or with `propagate` each relative motion
/// `P_i⁻¹·P_{i+1}·T` chained from the first pose. A scale on the right scales the pose's offset.
pub fn transform(t: &mut Trajectory, s: &Similarity, right: bool, propagate: bool) {
    let q_t = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&s.rotation));
    let n = t.len();
    let ident = vec![UnitQuaternion::identity(); n];
    let q: Vec<UnitQuaternion<f64>> = t.orientations.clone().unwrap_or(ident);
    let mut out_q = q.clone();
    if !right {
        for (p, o) in t.positions.iter_mut().zip(out_q.iter_mut()) {
            *p = s.rotation * (*p * s.scale) + s.translation;
            *o = q_t * *o;
        }
    } else if !propagate {
        for (k, p) in t.positions.iter_mut().enumerate() {
            *p += q[k] * s.translation;
            out_q[k] = q[k] * q_t;
        }
    } else {
        let p0 = t.positions.clone();
        for k in 1..n {
            // rel = P_{k-1}⁻¹ P_k T; new_k = new_{k-1} rel.
            let (dq, dp) = (
                q[k - 1].inverse() * q[k],
                q[k - 1].inverse() * (p0[k] - p0[k - 1]),
            );
            let (rq, rp) = (dq * q_t, dp + dq * s.translation);
            let (prev_q, prev_p) = (out_q[k - 1], t.positions[k - 1]);
            out_q[k] = prev_q * rq;
            t.positions[k] = prev_p + prev_q * rp;
        }
    }
    if t.orientations.is_some() || right {
        t.orientations = Some(out_q);
    }
}

/// evo_traj's `--merge`: every trajectory's samples in one, sorted by stamp (a repeated stamp keeps
/// its first sample, counted in the rows).
pub fn merge(ts: Vec<TrajInput>) -> TrajInput {
    let mut rows = RowAudit::default();
    let with_q = ts.iter().all(|t| t.trajectory.orientations.is_some());
    let mut m = Trajectory::new(with_q);
    let path = ts.first().map(|t| t.path.clone()).unwrap_or_default();
    for t in &ts {
        rows.add(&t.rows);
        for i in 0..t.trajectory.len() {
            m.push(
                t.trajectory.stamps_ns[i],
                t.trajectory.positions[i],
                t.trajectory.orientations.as_ref().map(|o| o[i]),
            );
        }
    }
    let audit = m.clean();
    rows.duplicate_stamp += audit.duplicate_stamp;
    TrajInput {
        name: "merged_trajectory".into(),
        path,
        trajectory: m,
        stamped: true,
        rows,
        checks: RawChecks::default(),
    }
}

/// evo's `--motion_filter DISTANCE ANGLE_DEGREES` on one trajectory.
pub fn motion_filter(t: &mut TrajInput, distance_m: f64, angle_deg: f64) -> Result<()> {
    let ids =
        crate::metrics::standard::filters::motion_filter_ids(&poses_of(t), distance_m, angle_deg)?;
    let tr = &t.trajectory;
    t.trajectory = Trajectory {
        stamps_ns: ids.iter().map(|&i| tr.stamps_ns[i as usize]).collect(),
        positions: ids.iter().map(|&i| tr.positions[i as usize]).collect(),
        orientations: tr
            .orientations
            .as_ref()
            .map(|o| ids.iter().map(|&i| o[i as usize]).collect()),
    };
    Ok(())
}

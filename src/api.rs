//! The library's API for programs: read a trajectory from anything the command line reads, evaluate a
//! request or trajectories already in memory, and each piece of the evaluation alone — the clock
//! offset, the Drift Error, evo's APE and RPE.
//!
//! Why a module of its own: it is the surface other programs (the Python package first) stand on. Its
//! functions and the types they take and give are re-exported at the crate root; a caller names
//! `trajdrift::read`, `trajdrift::ape`, never a path into the modules below, which may move.
//!
//! How: every function is a thin door onto the code the command line runs, so a number from here is the
//! command line's number. [`read`] is the evaluation's input pass (one streaming pass over a recording,
//! the text readers for files); [`evaluate`] is `trajdrift eval`'s job (`job::run`, its roles
//! resolved by `eval::roles`); [`evaluate_trajectories`],
//! [`time_offset`] and [`drift_error`] are the same evaluation job on trajectories in memory; [`ape`]
//! and [`rpe`] are the core's evo-exact metrics (`trajdrift ape`/`rpe`). Nothing here prints, draws a
//! progress bar or writes a file.
//!
//! Units: stamps are integer nanoseconds in a [`Trajectory`]; evo's metrics take seconds as `f64`
//! ([`Poses`]), converted the way evo's reader of the source converts them ([`TrajectoryRead::poses`]),
//! because evo associates poses on those floats.

use std::path::{Path, PathBuf};

use nalgebra::Matrix3;

use crate::error::{Error, Result};
use crate::eval::inputs::{Inputs, Loaded};
use crate::evo::metric_result::ValueAxes;
use crate::metrics::standard::{evaluate_detailed, Metric};
use crate::report::json::{DriftErrorReport, Report, TimeOffsetReport};
use crate::sources::open::is_recording;
use crate::sources::text::read_text_audited;
use crate::trajectory::rows::RowAudit;
use crate::trajectory::Trajectory;

pub use crate::eval::config::{EvalConfig, LeverSpec, NamedInput, TrajectoryInput};
pub use crate::metrics::standard::poses::Rotations;
pub use crate::metrics::standard::{
    Alignment, AlignmentReport, DeltaReport, DeltaUnit, ErrorStats, MetricResult, PairSelection,
    Pipeline, Plane, PoseRelation, Poses, StampSeconds, SyncMethod,
};
pub use crate::params::{ParamSpec, Parameters, ValueKind, SPECS};
pub use crate::sources::mapped_csv::CsvMapping;
pub use crate::sources::text::{TextFormat, TextOptions};
pub use crate::sources::StampSource;

/// The one-line message the command line prints after `error: ` for `e`: each cause said once, control
/// characters from file names escaped.
pub fn error_message(e: &Error) -> String {
    let mut line = e.to_string();
    let mut cause = std::error::Error::source(e);
    while let Some(c) = cause {
        let text = c.to_string();
        if !line.contains(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
        cause = c.source();
    }
    crate::report::escape::escape_line(&line)
}

/// How [`read`] reads a source.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOptions {
    /// Recordings: the header stamp (when the sensor measured, the default) or the log stamp (when the
    /// recorder received the message).
    pub stamp: StampSource,
    /// NavSatFix topics: the ENU origin (latitude °, longitude °, height m); default the first valid fix.
    pub origin: Option<[f64; 3]>,
    /// Text files: the format (default picked per file), the CSV column mapping, KITTI's `times.txt`.
    pub text: TextOptions,
}

/// A trajectory [`read`] from a recording or a file, with what is known of its source.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryRead {
    /// The stamps, positions and (when the source has them) orientations. From a recording, or a
    /// EuRoC, CSV or KITTI file: sorted by stamp, a repeated stamp or a row not finite dropped (counted
    /// in `rows`). From a TUM file: its rows as written, as evo reads them (the evaluation sorts them
    /// and drops the repeats itself; `rows` says how many).
    pub trajectory: Trajectory,
    /// The name an evaluation gives it: the topic without its leading `/`, or the file stem.
    pub name: String,
    /// The topic (or `/tf:PARENT:CHILD` chain), or the file, as reports write it.
    pub source: String,
    /// The message type, or the text format (`tum`, `kitti`, `euroc`, `csv`).
    pub type_name: String,
    /// How evo's reader of this source turns its stamps into seconds: `Decimal` for TUM and CSV text,
    /// `NanosOverE9` for EuRoC's CSV, `SecPlusNanos` for recordings; `None` for a KITTI pose file
    /// without times, which evo pairs by index (its stamps here are frame `i` at `i · 0.1 s`).
    pub stamp_seconds: Option<StampSeconds>,
    /// KITTI pose files: the rotation matrices as written (evo uses them so; `trajectory` holds their
    /// nearest rotations). `None` for every other source.
    pub rotation_matrices: Option<Vec<Matrix3<f64>>>,
    /// Rows read, dropped per reason, stamps going back.
    pub rows: RowAudit,
    /// What the user must see beside the trajectory: a recording cut short (`truncated_recording`,
    /// the samples up to its last complete record are read).
    pub warnings: Vec<crate::Warning>,
}

impl TrajectoryRead {
    /// evo's form of this trajectory, for [`ape`] and [`rpe`]: stamps in seconds as evo's reader of
    /// the source gives them, and KITTI's rotation matrices as written.
    pub fn poses(self) -> Poses {
        let matrices = self.rotation_matrices;
        let mut poses = Poses::from_trajectory(self.trajectory, self.stamp_seconds);
        if let Some(m) = matrices {
            poses.rotations = Some(Rotations::Matrices(m));
        }
        poses
    }

    /// This trajectory as an input of [`evaluate_trajectories`].
    pub fn named(self) -> NamedTrajectory {
        NamedTrajectory {
            name: self.name,
            source: self.source,
            type_name: self.type_name,
            trajectory: self.trajectory,
            lever_m: None,
        }
    }
}

/// Reads one trajectory from anything the command line reads: a `topic` (or a `/tf:PARENT:CHILD` chain)
/// of a recording — MCAP, ROS 1 bag, rosbag2 folder, or a mission of several recordings or a folder of
/// them (all of `sources`) — or, with no topic, one text file (TUM, KITTI, EuRoC, CSV).
///
/// The same readers and the same pass as `trajdrift eval`: a recording is streamed once, memory grows
/// with the samples kept. Errors are the command line's one-line messages (a missing topic lists the
/// topics there are).
///
/// ```
/// use trajdrift::{read, ReadOptions};
///
/// let rec = ["fixtures/sim_ground/mission.mcap"];
/// let reference = read(&rec, Some("/reference/position"), &ReadOptions::default())?;
/// assert_eq!(reference.name, "reference/position");
/// assert_eq!(reference.type_name, "geometry_msgs/msg/PointStamped");
/// assert!(reference.trajectory.len() > 1000);
/// assert!(reference.trajectory.orientations.is_none()); // positions only
///
/// let missing = read(&rec, Some("/nope"), &ReadOptions::default()).unwrap_err();
/// assert!(missing.to_string().contains("topic /nope not found"));
/// # Ok::<(), trajdrift::Error>(())
/// ```
pub fn read<P: AsRef<Path>>(
    sources: &[P],
    topic: Option<&str>,
    options: &ReadOptions,
) -> Result<TrajectoryRead> {
    let paths: Vec<PathBuf> = sources.iter().map(|p| p.as_ref().to_path_buf()).collect();
    let Some(first) = paths.first() else {
        return Err(Error::InvalidArgument(
            "read: give a recording (or the files of a mission) or a text trajectory file".into(),
        ));
    };
    let Some(topic) = topic else {
        if paths.len() > 1 || is_recording(first) {
            return Err(Error::InvalidArgument(format!(
                "{}: a recording holds many trajectories; name the topic ({})",
                first.display(),
                trajectory_topics(&paths)
            )));
        }
        return read_file(first, &options.text);
    };
    let mut config = EvalConfig::new(Some(first.clone()), NamedInput::topic(topic), Vec::new());
    config.more_recordings = paths[1..].to_vec();
    config.params.stamp = Some(options.stamp);
    config.params.origin = options.origin;
    config.text = options.text.clone();
    config.keep_orientations = true;
    let inputs = crate::eval::inputs::load(&config, &|_| {})?;
    let r = inputs.reference;
    Ok(TrajectoryRead {
        trajectory: r.trajectory,
        name: r.name,
        source: r.label,
        type_name: r.type_name,
        stamp_seconds: Some(StampSeconds::SecPlusNanos),
        rotation_matrices: None,
        rows: r.rows,
        warnings: inputs.warnings,
    })
}

/// The trajectory topics of a recording, for the message that asks for one.
fn trajectory_topics(paths: &[PathBuf]) -> String {
    let topics = crate::sources::open_all(paths).and_then(|s| s.topics());
    match topics {
        Ok(t) => {
            let readable: Vec<String> = t
                .into_iter()
                .filter(|t| t.readable)
                .map(|t| t.topic)
                .collect();
            if readable.is_empty() {
                "it has no topic trajdrift reads as a trajectory; `trajdrift topics` lists its channels and TF chains".into()
            } else {
                format!("trajectories: {}", readable.join(", "))
            }
        }
        Err(_) => "`trajdrift topics` lists them".into(),
    }
}

/// One text trajectory file, with evo's stamp conversion for its format.
fn read_file(path: &Path, text: &TextOptions) -> Result<TrajectoryRead> {
    let format = match text.format {
        Some(f) => f,
        None => crate::sources::text::detect_format(path)?,
    };
    let (trajectory, format, rows) = if format == TextFormat::Tum {
        // The rows as written, as evo reads them; `rows` counts what an evaluation sorts or drops.
        let trajectory = crate::sources::tum::read_tum_rows(path)?;
        let rows = trajectory.clone().clean();
        (trajectory, format, rows)
    } else {
        read_text_audited(path, text)?
    };
    let (stamp_seconds, rotation_matrices) = match format {
        TextFormat::Kitti => (
            text.kitti_times.as_ref().map(|_| StampSeconds::Decimal),
            Some(kitti_matrices(path, &rows)?),
        ),
        TextFormat::Euroc => (Some(StampSeconds::NanosOverE9), None),
        TextFormat::Tum | TextFormat::Csv => (Some(StampSeconds::Decimal), None),
    };
    let input = NamedInput::file(&path.to_string_lossy());
    Ok(TrajectoryRead {
        trajectory,
        name: input.name,
        source: path.display().to_string(),
        type_name: format.as_str().into(),
        stamp_seconds,
        rotation_matrices,
        rows,
        warnings: Vec::new(),
    })
}

/// A KITTI file's rotation matrices as written, when every row was kept (a dropped row would pair
/// the matrices with the wrong positions: then `None` is no option, the error says so).
fn kitti_matrices(path: &Path, rows: &RowAudit) -> Result<Vec<Matrix3<f64>>> {
    if rows.dropped() > 0 {
        return Err(Error::Text {
            path: path.to_path_buf(),
            line: 0,
            detail: format!(
                "{} of its poses are not finite or out of range",
                rows.dropped()
            ),
            hint: "KITTI poses are paired by index; repair the file".into(),
        });
    }
    Ok(crate::sources::kitti::read_kitti_matrices(path)?
        .into_iter()
        .map(|(r, _)| r)
        .collect())
}

/// Everything `trajdrift eval` is asked, as a program gives it; [`EvalRequest::config`] turns it into
/// the evaluation's [`EvalConfig`] the way the command line does (a preset picks the topics and lays
/// its parameters under the given ones).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EvalRequest {
    /// The recording, or the files (or folder) of one mission; empty with text files only.
    pub recordings: Vec<PathBuf>,
    /// The reference: a topic of the recording, or a text file. `None`: the preset's.
    pub reference: Option<NamedInput>,
    /// The estimates. Empty: the preset's.
    pub estimates: Vec<NamedInput>,
    /// A preset name (`grandtour`, …) or a preset file.
    pub preset: Option<String>,
    /// The evaluation parameters given (unset ones: the preset's, else the defaults).
    pub parameters: Parameters,
    /// How text files are read.
    pub text: TextOptions,
    /// `--reference-lever`.
    pub reference_lever: Option<LeverSpec>,
    /// `--estimate-lever [NAME=]…`: `None` as name applies to every estimate without a named one.
    pub estimate_levers: Vec<(Option<String>, LeverSpec)>,
}

impl EvalRequest {
    /// The evaluation's configuration, and the notes the user should see (a preset's estimate absent
    /// from the recording).
    pub fn config(self) -> Result<(EvalConfig, Vec<String>)> {
        let preset = self
            .preset
            .as_deref()
            .map(crate::eval::preset::Preset::load)
            .transpose()?;
        let roles = crate::eval::roles::resolve(
            &self.recordings,
            self.reference,
            self.estimates,
            preset.as_ref(),
            "give --reference TOPIC or --reference-file FILE",
        )?;
        let notes = roles.notes.clone();
        let mut c = roles.config(&self.recordings, &[&self.parameters]);
        c.text = self.text;
        c.reference_lever = self.reference_lever;
        c.estimate_levers = self.estimate_levers;
        Ok((c, notes))
    }
}

/// Runs the evaluation `trajdrift eval` runs for `config`, quietly: each estimate's clock offset, its
/// Drift Error at every window and evo's APE/RPE (`metrics`), in the typed report whose JSON form is
/// `--json`'s. Warnings the user must see are in [`Report::warnings`].
///
/// ```
/// use trajdrift::{evaluate, EvalRequest, NamedInput};
///
/// let (config, _notes) = EvalRequest {
///     recordings: vec!["fixtures/sim_ground/mission.mcap".into()],
///     reference: Some(NamedInput::topic("/reference/position")),
///     estimates: vec![NamedInput::topic("lio=/estimate/odom")],
///     ..Default::default()
/// }
/// .config()?;
/// let report = evaluate(&config)?;
/// let lio = &report.estimates[0];
/// assert_eq!(lio.name, "lio");
/// assert!((lio.time_offset.offset_s - 0.2).abs() < 0.01); // the truth: +0.2 s
/// let de = lio.drift_error[0].rmse.unwrap();
/// assert!((de - 0.02).abs() < 0.003); // the truth: a 2 % scale error
/// # Ok::<(), trajdrift::Error>(())
/// ```
pub fn evaluate(config: &EvalConfig) -> Result<Report> {
    crate::job::run(config, &crate::job::JobOutputs::default(), &|_| {}).map(|done| done.report)
}

/// One trajectory of an evaluation in memory: its name, what the report says it came from, and its
/// lever arm (the sensor's position in the body frame, metres; `--estimate-lever`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NamedTrajectory {
    pub name: String,
    /// A topic or a file as the report writes it (may be empty).
    pub source: String,
    /// A message type or a text format (may be empty).
    pub type_name: String,
    pub trajectory: Trajectory,
    pub lever_m: Option<[f64; 3]>,
}

impl NamedTrajectory {
    /// `trajectory` named `name`, nothing else known.
    pub fn new(name: &str, trajectory: Trajectory) -> Self {
        NamedTrajectory {
            name: name.into(),
            trajectory,
            ..Default::default()
        }
    }
}

/// The evaluation of trajectories already in memory (read by [`read`], or made by a program): the
/// same job and the same [`Report`] as [`evaluate`], with the same parameter checks. Each trajectory
/// is sorted by stamp and rows with a repeated stamp or a coordinate that is not finite are dropped
/// first (counted in the report's `rows`), as the readers do.
///
/// ```
/// use trajdrift::{evaluate_trajectories, read, Parameters, ReadOptions};
///
/// let rec = ["fixtures/sim_ground/mission.mcap"];
/// let o = ReadOptions::default();
/// let reference = read(&rec, Some("/reference/position"), &o)?.named();
/// let estimate = read(&rec, Some("/estimate/odom"), &o)?.named();
/// let parameters = Parameters { window: Some(vec![5.0, 10.0]), ..Default::default() };
/// let report = evaluate_trajectories(reference, vec![estimate], &parameters)?;
/// assert_eq!(report.estimates[0].drift_error.len(), 2);
///
/// let bad = Parameters { grid: Some(1e-9), ..Default::default() };
/// let e = evaluate_trajectories(read(&rec, Some("/reference/position"), &o)?.named(),
///     vec![read(&rec, Some("/estimate/odom"), &o)?.named()], &bad).unwrap_err();
/// assert!(e.to_string().starts_with("--grid 1e-9: out of range"));
/// # Ok::<(), trajdrift::Error>(())
/// ```
pub fn evaluate_trajectories(
    reference: NamedTrajectory,
    estimates: Vec<NamedTrajectory>,
    parameters: &Parameters,
) -> Result<Report> {
    let input = |n: &NamedTrajectory| NamedInput {
        name: n.name.clone(),
        input: TrajectoryInput::TumFile(PathBuf::from(&n.source)),
    };
    let mut config = EvalConfig::new(
        None,
        input(&reference),
        estimates.iter().map(input).collect(),
    );
    config.params = parameters.clone();
    config.validate()?;
    let loaded = |n: NamedTrajectory| {
        let mut trajectory = n.trajectory;
        let rows = trajectory.clean();
        Loaded {
            name: n.name,
            label: n.source,
            type_name: n.type_name,
            trajectory,
            dropped_samples: rows.dropped(),
            rows,
            geodetic_origin: None,
            lever_m: n.lever_m,
        }
    };
    let path = if reference.source.is_empty() {
        "<memory>".to_string()
    } else {
        reference.source.clone()
    };
    let inputs = Inputs {
        reference: loaded(reference),
        estimates: estimates.into_iter().map(loaded).collect(),
        warnings: Vec::new(),
        path,
        bytes: 0,
    };
    crate::eval::evaluate_loaded(&config, inputs).map(|(report, _)| report)
}

/// The clock offset of `estimate` against `reference` (t_est + offset = reference clock), as `eval`
/// finds it with `parameters` (`offset_method`, `offset_model`, `max_offset`, …): the method's answer,
/// its σ, the clock model, every method that ran and why the answer was taken.
///
/// ```
/// use trajdrift::{read, time_offset, Parameters, ReadOptions, TimeOffsetStatus};
///
/// let rec = ["fixtures/sim_ground/mission.mcap"];
/// let o = ReadOptions::default();
/// let reference = read(&rec, Some("/reference/position"), &o)?.trajectory;
/// let estimate = read(&rec, Some("/estimate/odom"), &o)?.trajectory;
/// let dt = time_offset(&reference, &estimate, &Parameters::default())?;
/// assert_eq!(dt.status, TimeOffsetStatus::Ok);
/// assert!((dt.offset_s - 0.2).abs() < 0.01 && dt.sigma_s.unwrap() < 0.01);
/// # Ok::<(), trajdrift::Error>(())
/// ```
pub fn time_offset(
    reference: &Trajectory,
    estimate: &Trajectory,
    parameters: &Parameters,
) -> Result<TimeOffsetReport> {
    let p = Parameters {
        metrics: Some(Vec::new()),
        ..parameters.clone()
    };
    one_estimate(reference, estimate, &p).map(|e| e.time_offset)
}

/// The Drift Error of `estimate` against `reference` at each window of `parameters` (default 5 m),
/// after the clock offset `eval` finds (or `time_offset` when given): one result per window.
///
/// ```
/// use trajdrift::{drift_error, read, Parameters, ReadOptions};
///
/// let rec = ["fixtures/sim_ground/mission.mcap"];
/// let o = ReadOptions::default();
/// let reference = read(&rec, Some("/reference/position"), &o)?.trajectory;
/// let estimate = read(&rec, Some("/estimate/odom"), &o)?.trajectory;
/// let de = drift_error(&reference, &estimate, &Parameters::default())?;
/// assert_eq!(de[0].window_m, 5.0);
/// assert!((de[0].rmse.unwrap() - 0.02).abs() < 0.003); // a 2 % scale error
/// # Ok::<(), trajdrift::Error>(())
/// ```
pub fn drift_error(
    reference: &Trajectory,
    estimate: &Trajectory,
    parameters: &Parameters,
) -> Result<Vec<DriftErrorReport>> {
    let p = Parameters {
        metrics: Some(vec![crate::metrics::standard::in_eval::EvalMetric::De]),
        ..parameters.clone()
    };
    one_estimate(reference, estimate, &p).map(|e| e.drift_error)
}

fn one_estimate(
    reference: &Trajectory,
    estimate: &Trajectory,
    parameters: &Parameters,
) -> Result<crate::report::json::EstimateReport> {
    let report = evaluate_trajectories(
        NamedTrajectory::new("reference", reference.clone()),
        vec![NamedTrajectory::new("estimate", estimate.clone())],
        parameters,
    )?;
    Ok(report
        .estimates
        .into_iter()
        .next()
        .expect("one estimate in, one out"))
}

/// evo's options of APE and RPE, with evo's names: what `evo.main_ape.ape`/`evo.main_rpe.rpe` take,
/// and the association `evo_ape`/`evo_rpe` make before them. `Default` is evo's command line's:
/// translation part, no alignment, `t_max_diff` 0.01 s.
#[derive(Debug, Clone, PartialEq)]
pub struct MetricOptions {
    pub pose_relation: PoseRelation,
    /// Umeyama SE(3) (with `correct_scale`: Sim(3)) on the associated positions.
    pub align: bool,
    /// With `align`: Sim(3); alone: the scale only.
    pub correct_scale: bool,
    /// Align on the first N pairs only (`None`: all, evo's -1).
    pub n_to_align: Option<usize>,
    /// The first estimate pose onto the first reference pose.
    pub align_origin: bool,
    /// 4-DoF alignment (yaw + translation) for gravity-aligned frames (not in evo).
    pub align_yaw: bool,
    /// Association: the largest stamp difference of a pair, seconds.
    pub t_max_diff_s: f64,
    /// Added to the estimate's stamps before association, seconds.
    pub t_offset_s: f64,
    pub sync: SyncMethod,
    /// Crop the reference on its own stamps, seconds.
    pub t_start_s: Option<f64>,
    pub t_end_s: Option<f64>,
    pub project_to_plane: Option<Plane>,
}

impl Default for MetricOptions {
    fn default() -> Self {
        let p = Pipeline::default();
        MetricOptions {
            pose_relation: PoseRelation::TransPart,
            align: false,
            correct_scale: false,
            n_to_align: p.n_to_align,
            align_origin: false,
            align_yaw: false,
            t_max_diff_s: p.t_max_diff_s,
            t_offset_s: p.t_offset_s,
            sync: p.sync,
            t_start_s: p.t_start_s,
            t_end_s: p.t_end_s,
            project_to_plane: p.project_to_plane,
        }
    }
}

impl MetricOptions {
    /// The core's pipeline for these options (the alignment chosen as `evo_ape` chooses it).
    pub fn pipeline(&self) -> Pipeline {
        Pipeline {
            alignment: match (
                self.align,
                self.correct_scale,
                self.align_origin,
                self.align_yaw,
            ) {
                (_, _, true, _) => Alignment::Origin,
                (_, _, _, true) => Alignment::YawTranslation,
                (true, true, ..) => Alignment::Sim3,
                (true, false, ..) => Alignment::Se3,
                (false, true, ..) => Alignment::ScaleOnly,
                _ => Alignment::None,
            },
            n_to_align: self.n_to_align,
            t_max_diff_s: self.t_max_diff_s,
            t_offset_s: self.t_offset_s,
            sync: self.sync,
            t_start_s: self.t_start_s,
            t_end_s: self.t_end_s,
            project_to_plane: self.project_to_plane,
        }
    }
}

/// An APE or RPE result and the arrays evo's result holds beside its statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct StandardResult {
    /// The statistics (evo's rmse, mean, median, std, min, max, sse), the alignment, the per-pair
    /// values (`values`, evo's `error_array`); its JSON form is `trajdrift ape --json`'s.
    pub result: MetricResult,
    /// The estimate's stamps of the values, seconds (evo's `timestamps`; `None` for paths).
    pub timestamps: Option<Vec<f64>>,
    /// `timestamps` from the first, seconds (evo's `seconds_from_start`).
    pub seconds_from_start: Option<Vec<f64>>,
    /// The reference's path length at each value, metres (evo's `distances_from_start`).
    pub distances_from_start: Vec<f64>,
    /// The estimate's path length at each value, metres (evo's `distances`).
    pub distances: Vec<f64>,
    /// RPE: the `(i, j)` pairs of associated poses each value compares.
    pub pairs: Option<Vec<(usize, usize)>>,
}

fn standard(
    reference: Poses,
    estimate: Poses,
    metric: Metric,
    options: &MetricOptions,
) -> Result<StandardResult> {
    let (result, evaluated) = evaluate_detailed(
        reference,
        estimate,
        metric,
        options.pose_relation,
        &options.pipeline(),
    )?;
    let axes = ValueAxes::of(&evaluated);
    Ok(StandardResult {
        result,
        timestamps: axes.timestamps,
        seconds_from_start: axes.seconds_from_start,
        distances_from_start: axes.distances_from_start,
        distances: axes.distances,
        pairs: evaluated.pairs,
    })
}

/// evo's absolute pose error: associate by time, align, `E_i = P_est,i⁻¹ · P_ref,i` reduced by the pose
/// relation, evo's statistics — equal to `evo_ape` with the same options to its printed decimals.
///
/// ```
/// use trajdrift::{ape, read, MetricOptions, ReadOptions};
///
/// let rec = ["fixtures/sim_ground/mission.mcap"];
/// let o = ReadOptions::default();
/// let reference = read(&rec, Some("/reference/position"), &o)?.poses();
/// // The estimate's clock runs 0.2 s behind: shift it, then associate at 20 ms.
/// let estimate = read(&rec, Some("/estimate/odom"), &o)?.poses();
/// let options = MetricOptions { align: true, correct_scale: true, t_offset_s: 0.2,
///     t_max_diff_s: 0.02, ..Default::default() };
/// let r = ape(reference, estimate, &options)?;
/// assert!(r.result.stats.rmse < 0.5);
/// assert_eq!(r.result.values.len(), r.result.stats.n);
/// # Ok::<(), trajdrift::Error>(())
/// ```
pub fn ape(reference: Poses, estimate: Poses, options: &MetricOptions) -> Result<StandardResult> {
    standard(reference, estimate, Metric::Ape, options)
}

/// evo's relative pose error over the pose pairs `pairs` selects (a delta in frames, metres, degrees or
/// radians; consecutive or all pairs), `E = (Q_i⁻¹Q_j)⁻¹(P_i⁻¹P_j)` reduced by the pose relation — equal to
/// `evo_rpe` with the same options to its printed decimals.
///
/// ```
/// use trajdrift::{read, rpe, DeltaUnit, MetricOptions, PairSelection, PoseRelation, ReadOptions};
///
/// let rec = ["fixtures/sim_ground/mission.mcap"];
/// let o = ReadOptions::default();
/// let reference = read(&rec, Some("/reference/position"), &o)?.poses();
/// let estimate = read(&rec, Some("/estimate/odom"), &o)?.poses();
/// // Positions only in the reference: the point distance over pairs 1 m apart.
/// let options = MetricOptions { pose_relation: PoseRelation::PointDistance, t_offset_s: 0.2,
///     t_max_diff_s: 0.02, ..Default::default() };
/// let pairs = PairSelection { delta: 1.0, unit: DeltaUnit::Meters, ..Default::default() };
/// let r = rpe(reference, estimate, &options, &pairs)?;
/// assert!(r.result.stats.mean < 0.1);
/// assert_eq!(r.pairs.unwrap().len(), r.result.values.len());
/// # Ok::<(), trajdrift::Error>(())
/// ```
pub fn rpe(
    reference: Poses,
    estimate: Poses,
    options: &MetricOptions,
    pairs: &PairSelection,
) -> Result<StandardResult> {
    standard(reference, estimate, Metric::Rpe(*pairs), options)
}

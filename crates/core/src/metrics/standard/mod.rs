//! The standard trajectory metrics beside Drift Error: APE and RPE with evo's conventions, so that a
//! number from `trajdrift ape`/`rpe` can replace one from `evo_ape`/`evo_rpe` to the last printed
//! decimal. The pipeline is evo's: crop the reference (`t_start`/`t_end`), associate by time (or pair by
//! index for KITTI paths), align the estimate, project to a plane, compute the per-pair errors, summarise.
//! See `docs/standard-metrics.md` for the conventions and the evo flag → trajdrift flag table.

pub(crate) mod ape;
pub mod associate;
pub mod filters;
pub mod in_eval;
pub(crate) mod kitti_drift;
pub mod poses;
pub(crate) mod relation;
pub(crate) mod rpe;
pub mod umeyama;

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::trajectory::Trajectory;
pub use associate::SyncMethod;
pub use poses::{Poses, StampSeconds};
pub use relation::PoseRelation;
pub use rpe::{DeltaUnit, PairSelection};
pub use umeyama::Similarity;

/// How the estimate is aligned onto the reference before the errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Alignment {
    #[default]
    None,
    /// `-a`: Umeyama SE(3) on positions.
    Se3,
    /// `-a -s`: Umeyama Sim(3).
    Sim3,
    /// `-s` alone: the Sim(3) scale only.
    ScaleOnly,
    /// `--align_origin`: first pose onto first pose.
    Origin,
    /// `--align-yaw`: yaw + translation (4-DoF), for gravity-aligned frames (not in evo).
    YawTranslation,
}

impl Alignment {
    /// Name as written in the JSON report.
    pub fn as_str(self) -> &'static str {
        match self {
            Alignment::None => "none",
            Alignment::Se3 => "se3",
            Alignment::Sim3 => "sim3",
            Alignment::ScaleOnly => "scale",
            Alignment::Origin => "origin",
            Alignment::YawTranslation => "yaw_translation",
        }
    }
}

/// A plane for `--project_to_plane`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    Xy,
    Xz,
    Yz,
}

/// Everything but the metric itself: association, alignment, projection.
#[derive(Debug, Clone, PartialEq)]
pub struct Pipeline {
    pub alignment: Alignment,
    /// `--n_to_align`: align on the first N pairs only.
    pub n_to_align: Option<usize>,
    /// `--t_max_diff`, seconds (evo: 0.01).
    pub t_max_diff_s: f64,
    /// `--t_offset` / `--time-offset`: added to the estimate's stamps for the association, seconds.
    pub t_offset_s: f64,
    pub sync: SyncMethod,
    /// `--t_start`/`--t_end`: crop the reference, its own stamps in seconds.
    pub t_start_s: Option<f64>,
    pub t_end_s: Option<f64>,
    pub project_to_plane: Option<Plane>,
}

impl Default for Pipeline {
    fn default() -> Self {
        Pipeline {
            alignment: Alignment::None,
            n_to_align: None,
            t_max_diff_s: 0.01,
            t_offset_s: 0.0,
            sync: SyncMethod::NearestTime,
            t_start_s: None,
            t_end_s: None,
            project_to_plane: None,
        }
    }
}

/// Which metric.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Metric {
    Ape,
    Rpe(PairSelection),
}

/// evo's statistics of the per-pair errors (population std, numpy's median).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    pub rmse: f64,
    pub mean: f64,
    pub median: f64,
    pub std: f64,
    pub min: f64,
    pub max: f64,
    pub sse: f64,
    pub n: usize,
}

impl ErrorStats {
    /// Summarises `values` (non-empty).
    pub fn of(values: &[f64]) -> Option<ErrorStats> {
        let s = crate::stats::summarize(values)?;
        Some(ErrorStats {
            rmse: s.rmse,
            mean: s.mean,
            median: s.median,
            std: s.std,
            min: s.min,
            max: s.max,
            sse: values.iter().map(|v| v * v).sum(),
            n: s.n,
        })
    }
}

/// The alignment applied, for the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlignmentReport {
    pub method: String,
    /// Row-major 3×3 rotation.
    pub rotation: [[f64; 3]; 3],
    pub translation_m: [f64; 3],
    pub scale: f64,
    /// Pairs the alignment was estimated on.
    pub poses_used: usize,
}

/// One APE or RPE result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MetricResult {
    /// `ape` or `rpe`.
    pub metric: String,
    /// evo's pose relation name.
    pub relation: String,
    /// The unit of the values (`m`, `deg`, `rad`, `%`, or empty).
    pub unit: String,
    pub alignment: AlignmentReport,
    /// Associated pose pairs (APE) or pose pairs compared (RPE).
    pub pairs: usize,
    /// RPE: the delta and its unit, and whether all pairs were used.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub delta: Option<DeltaReport>,
    /// The offset added to the estimate's stamps before association, seconds.
    pub time_offset_s: f64,
    pub stats: ErrorStats,
    /// The per-pair values (not serialised; for plots and sweeps).
    #[serde(skip)]
    pub values: Vec<f64>,
}

/// The RPE delta as used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeltaReport {
    pub delta: f64,
    pub unit: String,
    pub all_pairs: bool,
    pub pairs_from_reference: bool,
}

/// Whether `metric` with `relation` reads orientations (and `alignment` uses them): RPE's translation
/// part is expressed in the body frame of its first pose, angle deltas need rotations, APE only for
/// the rotation relations.
pub fn needs_orientation(metric: Metric, relation: PoseRelation, alignment: Alignment) -> bool {
    let point = matches!(
        relation,
        PoseRelation::PointDistance | PoseRelation::PointDistanceErrorRatio
    );
    alignment == Alignment::Origin
        || match metric {
            Metric::Rpe(s) if matches!(s.unit, DeltaUnit::Degrees | DeltaUnit::Radians) => true,
            Metric::Rpe(_) => !point,
            Metric::Ape => relation.needs_orientation(),
        }
}

/// Computes `metric` of `estimate` against `reference`, evo's way. Stamped trajectories are associated
/// by time; paths (`stamps_s: None`, KITTI) are paired by index and must have the same length.
pub fn evaluate(
    mut reference: Poses,
    mut estimate: Poses,
    metric: Metric,
    relation: PoseRelation,
    pipeline: &Pipeline,
) -> Result<MetricResult> {
    let needs_rot = check_rotations(&reference, &estimate, metric, relation)?;
    if !needs_rot && pipeline.alignment != Alignment::Origin {
        // Not read: free them before association (half the memory at millions of poses).
        reference.rotations = None;
        estimate.rotations = None;
    }
    let (reference, estimate) = pair_up(reference, estimate, pipeline)?;
    evaluate_paired(reference, estimate, metric, relation, pipeline)
}

/// [`evaluate`] with the estimate borrowed: only its poses paired with the reference are copied (an
/// evaluation that already holds a 200 Hz estimate does not need a second copy of it per metric).
pub fn evaluate_borrowed(
    mut reference: Poses,
    estimate: &Poses,
    metric: Metric,
    relation: PoseRelation,
    pipeline: &Pipeline,
) -> Result<MetricResult> {
    let needs_rot = check_rotations(&reference, estimate, metric, relation)?;
    let unread = !needs_rot && pipeline.alignment != Alignment::Origin;
    if unread {
        reference.rotations = None;
    }
    let (reference, mut estimate) = if reference.stamps_s.is_some() && estimate.stamps_s.is_some() {
        let reference = reference.crop(pipeline.t_start_s, pipeline.t_end_s);
        associate::associate_borrowed(
            reference,
            estimate,
            pipeline.t_max_diff_s,
            pipeline.t_offset_s,
            pipeline.sync,
        )?
    } else {
        pair_up(reference, estimate.clone(), pipeline)?
    };
    if unread {
        estimate.rotations = None;
    }
    evaluate_paired(reference, estimate, metric, relation, pipeline)
}

/// Whether `metric` with `relation` reads rotations; the one-line error when it does and a side has
/// none.
fn check_rotations(
    reference: &Poses,
    estimate: &Poses,
    metric: Metric,
    relation: PoseRelation,
) -> Result<bool> {
    let point_relation = matches!(
        relation,
        PoseRelation::PointDistance | PoseRelation::PointDistanceErrorRatio
    );
    let (needs_rot, what) = match metric {
        Metric::Rpe(s) if matches!(s.unit, DeltaUnit::Degrees | DeltaUnit::Radians) => {
            (true, format!("-u {}", s.unit.as_str()))
        }
        // RPE's translation part is expressed in the body frame of pose i.
        Metric::Rpe(_) => (!point_relation, format!("RPE -r {}", relation.as_str())),
        Metric::Ape => (
            relation.needs_orientation(),
            format!("-r {}", relation.as_str()),
        ),
    };
    if needs_rot && (reference.rotations.is_none() || estimate.rotations.is_none()) {
        return Err(rpe::needs_orientation(&what));
    }
    Ok(needs_rot)
}

/// The poses a result was computed on (associated, aligned, projected) and RPE's pairs: what evo's
/// result file (`--save_results`) and its figures are made of.
#[derive(Debug, Clone)]
pub struct Evaluated {
    pub reference: Poses,
    pub estimate: Poses,
    /// RPE: the `(i, j)` pose pairs of the values, in their order (pairs skipped by
    /// `point_distance_error_ratio` left out, as evo leaves them out).
    pub pairs: Option<Vec<rpe::Pair>>,
}

/// [`evaluate`], also returning the poses and pairs the values come from.
pub fn evaluate_detailed(
    reference: Poses,
    estimate: Poses,
    metric: Metric,
    relation: PoseRelation,
    pipeline: &Pipeline,
) -> Result<(MetricResult, Evaluated)> {
    check_rotations(&reference, &estimate, metric, relation)?;
    let (reference, estimate) = pair_up(reference, estimate, pipeline)?;
    let (result, kept) =
        evaluate_paired_kept(reference, estimate, metric, relation, pipeline, true)?;
    Ok((result, kept.expect("kept on request")))
}

/// Alignment, errors and statistics of poses already paired.
fn evaluate_paired(
    reference: Poses,
    estimate: Poses,
    metric: Metric,
    relation: PoseRelation,
    pipeline: &Pipeline,
) -> Result<MetricResult> {
    evaluate_paired_kept(reference, estimate, metric, relation, pipeline, false).map(|r| r.0)
}

/// [`evaluate_paired`], keeping the poses and pairs when `keep`.
fn evaluate_paired_kept(
    reference: Poses,
    mut estimate: Poses,
    metric: Metric,
    relation: PoseRelation,
    pipeline: &Pipeline,
    keep: bool,
) -> Result<(MetricResult, Option<Evaluated>)> {
    let alignment = align(&reference, &mut estimate, pipeline)?;
    let (reference, estimate) = match pipeline.project_to_plane {
        Some(p) => (project(&reference, p), project(&estimate, p)),
        None => (reference, estimate),
    };
    let mut kept_pairs = None;
    let (values, delta) = match metric {
        Metric::Ape => (ape::ape_errors(&reference, &estimate, relation)?, None),
        Metric::Rpe(sel) => {
            let (v, pairs) = rpe::rpe_errors(&reference, &estimate, relation, &sel)?;
            if keep {
                kept_pairs = Some(match relation {
                    PoseRelation::PointDistanceErrorRatio => pairs
                        .into_iter()
                        .filter(|&(i, j)| reference.positions[i] != reference.positions[j])
                        .collect(),
                    _ => pairs,
                });
            }
            let d = DeltaReport {
                delta: sel.delta,
                unit: sel.unit.as_str().into(),
                all_pairs: sel.all_pairs,
                pairs_from_reference: sel.from_reference,
            };
            (v, Some(d))
        }
    };
    let stats = ErrorStats::of(&values).ok_or_else(|| {
        Error::Metric(
            "no error value could be computed (no pair, or all reference pair distances are 0)"
                .into(),
        )
    })?;
    let result = MetricResult {
        metric: match metric {
            Metric::Ape => "ape".into(),
            Metric::Rpe(_) => "rpe".into(),
        },
        relation: relation.as_str().into(),
        unit: relation.unit().into(),
        alignment,
        pairs: values.len(),
        delta,
        time_offset_s: pipeline.t_offset_s,
        stats,
        values,
    };
    let kept = keep.then_some(Evaluated {
        reference,
        estimate,
        pairs: kept_pairs,
    });
    Ok((result, kept))
}

/// The library entry for a time-offset sweep: `metric` of `estimate` with its stamps shifted by
/// `offset_s` (t_est + Δt) before association, trajectories as trajdrift reads them (stamps as decimal
/// seconds).
pub fn evaluate_with_offset(
    reference: &Trajectory,
    estimate: &Trajectory,
    offset_s: f64,
    metric: Metric,
    relation: PoseRelation,
    pipeline: &Pipeline,
) -> Result<MetricResult> {
    let conv = Some(StampSeconds::Decimal);
    let p = Pipeline {
        t_offset_s: offset_s,
        ..pipeline.clone()
    };
    evaluate(
        Poses::from_trajectory(reference.clone(), conv),
        Poses::from_trajectory(estimate.clone(), conv),
        metric,
        relation,
        &p,
    )
}

/// Crops the reference and associates (stamped), or checks the index pairing (paths).
fn pair_up(reference: Poses, estimate: Poses, p: &Pipeline) -> Result<(Poses, Poses)> {
    if reference.stamps_s.is_some() && estimate.stamps_s.is_some() {
        let reference = reference.crop(p.t_start_s, p.t_end_s);
        return associate::associate(reference, estimate, p.t_max_diff_s, p.t_offset_s, p.sync);
    }
    if reference.len() != estimate.len() {
        return Err(Error::Metric(format!(
            "KITTI pose files are paired by index: the reference has {} poses and the estimate {}; pass files of the same sequence",
            reference.len(),
            estimate.len()
        )));
    }
    Ok((reference, estimate))
}

/// Aligns `estimate` in place and reports the similarity used.
fn align(reference: &Poses, estimate: &mut Poses, p: &Pipeline) -> Result<AlignmentReport> {
    let n = p
        .n_to_align
        .map_or(estimate.len(), |n| n.min(estimate.len()));
    let (x, y) = (&estimate.positions[..n], &reference.positions[..n]);
    let sim = match p.alignment {
        Alignment::None => Similarity::identity(),
        Alignment::Se3 => umeyama::umeyama(x, y, false)?,
        Alignment::Sim3 => umeyama::umeyama(x, y, true)?,
        Alignment::ScaleOnly => Similarity {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
            scale: umeyama::umeyama(x, y, true)?.scale,
        },
        Alignment::Origin => umeyama::origin(reference, estimate)?,
        Alignment::YawTranslation => umeyama::yaw_translation(x, y)?,
    };
    sim.apply(estimate);
    let r = sim.rotation;
    Ok(AlignmentReport {
        method: p.alignment.as_str().into(),
        rotation: [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]),
        translation_m: [sim.translation.x, sim.translation.y, sim.translation.z],
        scale: sim.scale,
        poses_used: if p.alignment == Alignment::None { 0 } else { n },
    })
}

/// evo's `project`: zero the plane's normal coordinate, keep only the rotation about the normal (its
/// static-xyz Euler angle).
fn project(p: &Poses, plane: Plane) -> Poses {
    let k = match plane {
        Plane::Xy => 2,
        Plane::Xz => 1,
        Plane::Yz => 0,
    };
    let mut out = p.clone();
    for x in &mut out.positions {
        x[k] = 0.0;
    }
    if p.rotations.is_some() {
        let mut axis = Vector3::zeros();
        axis[k] = 1.0;
        let r = (0..p.len())
            .map(|i| {
                let a = euler_sxyz(&p.rotation(i))[k];
                *nalgebra::Rotation3::from_scaled_axis(axis * a).matrix()
            })
            .collect();
        out.rotations = Some(poses::Rotations::Matrices(r));
    }
    out
}

/// `transformations.euler_from_matrix(m, "sxyz")`.
fn euler_sxyz(m: &Matrix3<f64>) -> [f64; 3] {
    let cy = (m[(0, 0)] * m[(0, 0)] + m[(1, 0)] * m[(1, 0)]).sqrt();
    if cy > f64::EPSILON * 4.0 {
        [
            m[(2, 1)].atan2(m[(2, 2)]),
            (-m[(2, 0)]).atan2(cy),
            m[(1, 0)].atan2(m[(0, 0)]),
        ]
    } else {
        [(-m[(1, 2)]).atan2(m[(1, 1)]), (-m[(2, 0)]).atan2(cy), 0.0]
    }
}

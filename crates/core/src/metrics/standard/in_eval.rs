//! The standard metrics inside `trajdrift eval`: on the estimate already shifted onto the reference
//! clock (the offset found by the evaluation), APE (SE(3) aligned, translation part), RPE over 1 m of
//! path (translation part), the GrandTour practice (RPE point distance over 1 m, from positions alone)
//! and, when asked, KITTI segment drift. Each is evo's computation with evo's defaults
//! (`t_max_diff` 0.01 s, pairs from the estimate); one that cannot be computed on these data (no
//! orientation, too short) is reported as a note instead of failing the evaluation.

use serde::{Deserialize, Serialize};

use super::kitti_drift::{kitti_drift, KittiDrift};
use super::{
    evaluate_borrowed, Alignment, DeltaUnit, Metric, MetricResult, PairSelection, Pipeline,
    PoseRelation, Poses, StampSeconds,
};
use crate::trajectory::Trajectory;

/// One metric `eval --metrics` can compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EvalMetric {
    /// Drift Error (the paper).
    De,
    /// evo's APE, SE(3) alignment, translation part.
    Ape,
    /// evo's RPE over 1 m, translation part and point distance.
    Rpe,
    /// KITTI segment drift.
    Kitti,
}

/// Which metrics `eval --metrics` computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MetricSet {
    pub de: bool,
    pub ape: bool,
    pub rpe: bool,
    pub kitti: bool,
}

impl Default for MetricSet {
    /// Drift Error, APE and RPE; KITTI drift only when asked (it needs 100 m of path and orientation).
    fn default() -> Self {
        MetricSet {
            de: true,
            ape: true,
            rpe: true,
            kitti: false,
        }
    }
}

impl MetricSet {
    /// The set holding exactly `items` (`--metrics de,ape,rpe,kitti`, any subset, any order).
    pub fn of(items: &[EvalMetric]) -> MetricSet {
        let has = |m: EvalMetric| items.contains(&m);
        MetricSet {
            de: has(EvalMetric::De),
            ape: has(EvalMetric::Ape),
            rpe: has(EvalMetric::Rpe),
            kitti: has(EvalMetric::Kitti),
        }
    }

    /// True when any standard metric is asked.
    pub fn any_standard(&self) -> bool {
        self.ape || self.rpe || self.kitti
    }
}

/// The standard metrics of one estimate, as reported beside its Drift Error.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StandardMetrics {
    /// APE, SE(3) Umeyama alignment, translation part, m.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub ape: Option<MetricResult>,
    /// RPE over 1 m of path, translation part, m.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rpe_1m: Option<MetricResult>,
    /// RPE point distance over 1 m (GrandTour practice), m: positions alone.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rpe_point_distance_1m: Option<MetricResult>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub kitti: Option<KittiDrift>,
    /// Why an asked metric is missing.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub notes: Vec<String>,
}

/// Computes the asked standard metrics of `estimate` (already on the reference clock) against
/// `reference`. Sensors of one robot are not sampled in phase, so the association differs from evo's
/// default in one way: the longer trajectory is interpolated at the matched stamps
/// (`--sync_method interpolation`) and `t_max_diff` is the sparser trajectory's median sample period
/// (at least evo's 0.01 s). The estimate is taken whole and held once: each metric copies only the
/// poses paired with the reference.
pub fn standard_metrics(
    reference: &Trajectory,
    estimate: Trajectory,
    set: &MetricSet,
) -> StandardMetrics {
    let conv = Some(StampSeconds::Decimal);
    let poses = |t: &Trajectory| Poses::from_trajectory(t.clone(), conv);
    let aligned = Pipeline {
        alignment: Alignment::Se3,
        sync: super::SyncMethod::Interpolation,
        t_max_diff_s: [reference, &estimate]
            .iter()
            .filter_map(|t| t.median_period_s())
            .fold(0.01, f64::max),
        ..Pipeline::default()
    };
    let oriented = reference.orientations.is_some() && estimate.orientations.is_some();
    let estimate = Poses::from_trajectory(estimate, conv);
    let rpe_1m = Metric::Rpe(PairSelection {
        delta: 1.0,
        unit: DeltaUnit::Meters,
        ..PairSelection::default()
    });
    let mut out = StandardMetrics::default();
    let mut run = |name: &str, metric: Metric, relation: PoseRelation| {
        // Without orientations an answer that needs them is known before copying millions of poses.
        let result = if !oriented && super::needs_orientation(metric, relation, aligned.alignment) {
            Err(super::rpe::needs_orientation(&format!(
                "RPE -r {}",
                relation.as_str()
            )))
        } else {
            evaluate_borrowed(poses(reference), &estimate, metric, relation, &aligned)
        };
        match result {
            Ok(r) => Some(r),
            Err(e) => {
                out.notes.push(format!("{name}: {e}"));
                None
            }
        }
    };
    if set.ape {
        out.ape = run("ape", Metric::Ape, PoseRelation::TransPart);
    }
    if set.rpe {
        out.rpe_1m = run("rpe_1m", rpe_1m, PoseRelation::TransPart);
        out.rpe_point_distance_1m =
            run("rpe_point_distance_1m", rpe_1m, PoseRelation::PointDistance);
    }
    if set.kitti {
        let pair = super::associate::associate_borrowed(
            poses(reference),
            &estimate,
            aligned.t_max_diff_s,
            0.0,
            aligned.sync,
        );
        match pair.and_then(|(r, e)| kitti_drift(&r, &e)) {
            Ok(k) => out.kitti = Some(k),
            Err(e) => out.notes.push(format!("kitti: {e}")),
        }
    }
    out
}

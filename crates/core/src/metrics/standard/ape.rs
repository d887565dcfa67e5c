//! Absolute pose error, as evo's `metrics.APE`: per associated pair, the error pose
//! `E = P_est⁻¹ · P_ref` reduced by the pose relation (translation part and point distance: the distance
//! between the positions).

use super::poses::Poses;
use super::relation::PoseRelation;
use crate::error::{Error, Result};

/// The per-pose APE values of two associated trajectories (same length).
pub fn ape_errors(reference: &Poses, estimate: &Poses, relation: PoseRelation) -> Result<Vec<f64>> {
    if reference.len() != estimate.len() {
        return Err(Error::Metric(format!(
            "APE pairs poses one to one: the reference has {} and the estimate {}",
            reference.len(),
            estimate.len()
        )));
    }
    let pos = reference.positions.iter().zip(&estimate.positions);
    match relation {
        PoseRelation::TransPart | PoseRelation::PointDistance => {
            Ok(pos.map(|(r, e)| (e - r).norm()).collect())
        }
        PoseRelation::PointDistanceErrorRatio => Err(Error::InvalidArgument(
            "-r point_distance_error_ratio is an RPE relation (evo's APE does not support it either)".into(),
        )),
        _ => Ok((0..reference.len())
            .map(|i| {
                let re_t = estimate.rotation(i).transpose();
                let r = re_t * reference.rotation(i);
                let t = re_t * (reference.positions[i] - estimate.positions[i]);
                relation.of_error_pose(&r, &t)
            })
            .collect()),
    }
}

//! Applies known extrinsics to an evaluation: every estimate is moved onto the reference's point of the
//! body (`--estimate-lever`, `--reference-lever`) before its curvature, time offset and Drift Error are
//! computed. The reference is never moved, so on a position-only reference `--reference-lever` only
//! names the point the estimates are moved to. See [`crate::trajectory::extrinsics`] for the convention.

use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::eval::inputs::Loaded;
use crate::report::json::ExtrinsicsReport;
use crate::trajectory::extrinsics::move_to_body_point;

/// Moves each estimate that has a lever (its own, or a reference lever) onto the reference's point.
/// The levers are those [`crate::eval::inputs::load`] resolved into [`Loaded::lever_m`] (`tf-static:`
/// ones read from the recording). Returns what was done, per estimate in order (`None` when no lever
/// applies). A position-only estimate that would have to move is refused with an error naming it.
pub fn apply_levers(
    reference: &Loaded,
    estimates: &mut [Loaded],
) -> Result<Vec<Option<ExtrinsicsReport>>> {
    let l_ref = reference.lever_m;
    estimates
        .iter_mut()
        .map(|est| {
            let l_est = est.lever_m;
            if l_est.is_none() && l_ref.is_none() {
                return Ok(None);
            }
            let (le, lr) = (l_est.unwrap_or([0.0; 3]), l_ref.unwrap_or([0.0; 3]));
            let moved = move_to_body_point(&est.trajectory, &Vector3::from(le), &Vector3::from(lr))
                .ok_or_else(|| {
                    Error::InvalidArgument(format!(
                        "{}: cannot move a position-only trajectory ({}, no orientation) by a lever arm; drop --estimate-lever/--reference-lever for it or use a topic with orientation (Odometry, PoseStamped)",
                        est.label, est.type_name
                    ))
                })?;
            est.trajectory = moved;
            Ok(Some(ExtrinsicsReport {
                estimate_lever_m: le,
                reference_lever_m: lr,
                moved_by_body_m: [le[0] - lr[0], le[1] - lr[1], le[2] - lr[2]],
                applied_before: "curvature, time_offset, drift_error".into(),
            }))
        })
        .collect()
}

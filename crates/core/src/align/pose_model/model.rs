//! Step 1 and the order of the rest (see `mod.rs`): the whole mission's fit, the model the
//! windows choose, the lead search where it runs, the final fit averaged over tilings and its σ.

use nalgebra::Vector3;

use super::lead::{lead_search, lead_searched, narrowed};
use super::mission::Mission;
use super::sigma::set_parameters;
use super::tilings::{over_tilings, Cuts};
use super::{
    scale_prior_m, PoseClock, Replaced, Signals, COARSE_STEP_S, MAX_ANSWER_SPREAD_S,
    MAX_DISAGREEMENT_S,
};
use crate::align::clock_model::OffsetModel;
use crate::align::offset_profile::ProfileParams;
use crate::align::pose_fit::{self, ClockShape, PoseData, PoseFit};

/// The clock model of the mission in `data` from the pose fit, starting at `start_s` (the signal
/// searches' answer; the other confident searches' answers `other_answers_s` widen the lead
/// search); `None` when the fit cannot be made (too few windows, no convergence, or an answer
/// farther than [`MAX_DISAGREEMENT_S`] from the start that the lead search did not find).
///
/// The Newton Jacobian is `data.params.jacobian_periods` wide; a caller whose fit cannot be made
/// may try [`pose_fit::NARROW_JACOBIAN_PERIODS`] (a gait the default's differences answer with
/// the wrong sign sends Newton away from the truth), and says so.
pub fn pose_clock_model(
    data: &PoseData<'_>,
    start_s: f64,
    other_answers_s: &[f64],
    profile_params: &ProfileParams,
    signals: Signals<'_>,
    forced: Option<OffsetModel>,
) -> Option<PoseClock> {
    // The reference's mean speed while it moves (a robot that stands half the mission still walks).
    let moving_speed_mps =
        crate::align::auto_params::moving_speed(data.ref_t, data.ref_p, data.params.max_gap_s)
            .map(|(v, _)| v);
    let data = PoseData {
        params: pose_fit::PoseFitParams {
            window_s: profile_params.window_s.or(data.params.window_s),
            scale_prior_m: scale_prior_m(moving_speed_mps),
            ..data.params
        },
        ..*data
    };
    let narrow_data = narrowed(&data);
    let windows = data.windows();
    if windows.len() < 3 {
        return None;
    }
    let mut mission = Mission {
        data: &data,
        // The profile's windows: the fits' own (disjoint), or every `--offset-step` seconds.
        profile_windows: data.profile_windows(profile_params.step_s),
        whole: whole_mission_fit(&data, &windows, start_s),
        windows,
        signals,
        forced,
    };
    let mut chosen = mission.choose(start_s)?;
    // The lead search, where the windows chose one constant clock, or a step or a drift of their
    // own (`lead_searched`): across a true clock step the constant trades its lever for Δt as
    // well, and the other segment's basin fits better, so a far constant replaces the chosen model
    // only when the profile measured from it chooses a constant too (a true step or drift stays).
    // A drift the final fit leaves below the resolution (`resolved`) becomes a constant after
    // this.
    // The near fit: the whole mission's, or without one the chosen constant's.
    let near = mission.whole.clone().or_else(|| chosen.fit.clone());
    let lead = lead_searched(chosen.model.model, mission.forced)
        .then(|| {
            let answers: Vec<f64> = std::iter::once(start_s)
                .chain(other_answers_s.iter().copied())
                .filter(|a| a.is_finite() && (a - start_s).abs() <= MAX_ANSWER_SPREAD_S)
                .collect();
            lead_search(
                &data,
                &mission.windows,
                &answers,
                near.as_ref(),
                moving_speed_mps?,
            )
        })
        .flatten();
    let mut replaced = None;
    if let Some(far) = lead.as_ref().and_then(|l| l.far(near.as_ref())) {
        let other = Mission {
            whole: Some(far),
            windows: mission.windows.clone(),
            profile_windows: mission.profile_windows.clone(),
            ..mission
        };
        // Where the default Jacobian leaves the profile from the far fit fewer than three
        // windows, it is measured on the narrow one (the caller's fallback for the near fit).
        let (other, c, narrow_windows) = match other.choose(start_s) {
            Some(c) => (other, Some(c), false),
            None => {
                let other = Mission {
                    data: &narrow_data,
                    ..other
                };
                let c = other.choose(start_s);
                (other, c, true)
            }
        };
        if let Some(c) = c.filter(|c| c.model.model == OffsetModel::Constant) {
            let first_s = chosen
                .fit
                .as_ref()
                .map_or(chosen.model.offset_s, |f| f.theta[0]);
            replaced = Some(Replaced {
                model: chosen.model.model,
                first_s,
                narrow_windows,
            });
            (mission, chosen) = (other, c);
        }
    }
    // Without a converged fit of the chosen model, its parameters stay those of the windows.
    let Some(last) = chosen.fit else {
        return mission
            .without_fit(chosen.profile, chosen.model, chosen.lever_m)
            .map(|pc| PoseClock { replaced, ..pc });
    };
    let (profile, mut model) = (chosen.profile, chosen.model);
    let last = mission.resolved(&mut model, last);
    let (last, cuts) = match model.model {
        OffsetModel::Constant => over_tilings(mission.data, last),
        _ => (last, Cuts::NONE),
    };
    let valley_s = match (&lead, model.model) {
        (Some(lead), OffsetModel::Constant) => lead.valley_s(&data, &last),
        _ => 0.0,
    };
    let beyond_lever = match (&lead, model.model) {
        (Some(lead), OffsetModel::Constant) => lead.beyond_lever(&data, &last),
        _ => None,
    };
    let sigma_parts = set_parameters(&mut model, &last, &profile, valley_s, cuts);
    model.describe();
    // θ₀'s σ as reported: the headline's, or the first segment's.
    let first_sigma_s = match model.model {
        OffsetModel::Piecewise => model.segments.first().map_or(model.sigma_s, |s| s.sigma_s),
        _ => model.sigma_s,
    };
    Some(PoseClock {
        profile,
        model,
        sigma_parts,
        outlier_windows: last.outliers.len(),
        first_offset: (last.theta[0], first_sigma_s),
        lever: (last.lever_m, last.lever_sigma_m),
        fit: Some(last),
        replaced,
        beyond_lever,
    })
}

/// Step 1: one Δt and the lever over every window from `start_s`, or, when that does not converge,
/// from the best of a coarse search within [`MAX_DISAGREEMENT_S`] of it
/// ([`pose_fit::coarse_start`], every [`COARSE_STEP_S`]); `None` when neither converges or the fit
/// lands farther than [`MAX_DISAGREEMENT_S`] from the start (another basin).
fn whole_mission_fit(
    data: &PoseData<'_>,
    windows: &[pose_fit::Window],
    start_s: f64,
) -> Option<PoseFit> {
    let from = |theta: f64| {
        pose_fit::fit(
            data,
            windows,
            ClockShape::Constant,
            vec![theta],
            Vector3::zeros(),
            true,
        )
        .filter(|w| w.converged && (w.theta[0] - start_s).abs() <= MAX_DISAGREEMENT_S)
    };
    from(start_s).or_else(|| {
        let coarse =
            pose_fit::coarse_start(data, windows, start_s, (MAX_DISAGREEMENT_S, COARSE_STEP_S))?;
        ((coarse - start_s).abs() >= COARSE_STEP_S)
            .then(|| from(coarse))
            .flatten()
    })
}

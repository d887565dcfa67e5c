//! Steps 2 to 4 (see `mod.rs`): the profile measured from a fit, the model chosen from it
//! and that model's fit; a drift below the resolution or steps the fit does not tell apart taken
//! back to the constant.

use nalgebra::Vector3;

use super::profile::{calibrated_profile, consistent_windows};
use super::sigma::steps_resolved;
use super::{
    PoseClock, Signals, DEEP_SEARCH_SIGMA_S, POSE_SIGMA_FLOOR_S, STEP_RESOLUTION_Z, WINDOW_SEARCH_S,
};
use crate::align::clock_model::{
    choose_model, locate_change, windows_offset_s, ClockModel, OffsetModel, Steps,
};
use crate::align::offset_profile::OffsetProfile;
use crate::align::pose_fit::{self, ClockShape, PoseData, PoseFit, WindowSearch};

/// One mission's pose fits: the data, the windows of the fits and of the profile, the whole
/// mission's constant fit, and what the model choice takes besides the profile.
pub(super) struct Mission<'a, 's> {
    pub(super) data: &'a PoseData<'a>,
    pub(super) windows: Vec<pose_fit::Window>,
    pub(super) profile_windows: Vec<pose_fit::Window>,
    pub(super) whole: Option<PoseFit>,
    pub(super) signals: Signals<'s>,
    pub(super) forced: Option<OffsetModel>,
}

/// A profile, the model chosen from it, and that model's fit.
pub(super) struct Chosen {
    pub(super) profile: OffsetProfile,
    pub(super) model: ClockModel,
    /// The chosen model's clock shape.
    pub(super) shape: ClockShape,
    /// The chosen model's fit with the lever over every window; `None` when it did not converge.
    pub(super) fit: Option<PoseFit>,
    /// The lever the profile's windows held, estimate body frame.
    pub(super) lever_m: Vector3<f64>,
}

impl Mission<'_, '_> {
    /// Steps 2 to 4: the profile, the model chosen from it and its fit. Measured from the whole
    /// mission's constant fit, or without one from `start_s` with no lever; measured again with
    /// the lever of the chosen model when that is not the constant, or when there was no constant
    /// fit.
    pub(super) fn choose(&self, start_s: f64) -> Option<Chosen> {
        // Without a whole-mission constant fit (a step or a large drift spoils it), the profile
        // starts without a lever from the signal searches' answer, each window searching its own.
        let (mut lever, mut scale) = self
            .whole
            .as_ref()
            .map_or((Vector3::zeros(), (1.0, 1.0)), |w| {
                (w.lever_m, (w.scale, w.jacobian_scale))
            });
        let mut clock = (
            ClockShape::Constant,
            vec![self.whole.as_ref().map_or(start_s, |w| w.theta[0])],
        );
        let mut pass = 0;
        loop {
            pass += 1;
            // The first pass proposes steps on the BIC alone; the second, measured under them, judges.
            let steps = if pass == 1 {
                Steps::Provisional
            } else {
                Steps::Resolved
            };
            let chosen = self.pass(lever, scale, &clock, steps)?;
            // A model other than the constant was chosen on windows whose lever came from a
            // constant fit (or none): the profile is measured again with the lever of the chosen
            // model.
            if let (1, Some(l)) = (pass, &chosen.fit) {
                if chosen.model.model != OffsetModel::Constant || self.whole.is_none() {
                    lever = l.lever_m;
                    scale = (l.scale, l.jacobian_scale);
                    clock = (chosen.shape, l.theta.clone());
                    continue;
                }
            }
            // Steps proposed but not measured again (their fit did not converge): judged now, on
            // the same profile.
            if pass == 1 && chosen.model.model == OffsetModel::Piecewise {
                return Some(self.decide(
                    chosen.profile,
                    (lever, scale, clock.1[0]),
                    Steps::Resolved,
                ));
            }
            return Some(chosen);
        }
    }

    /// One pass: the profile with the lever `lever` held (the mission's scale and the scale of
    /// the clock column, `scale`: [`PoseFit::jacobian_scale`]), each window started from the clock
    /// `clock`, and what [`Self::decide`] makes of it. `None` with fewer than three windows in the profile.
    fn pass(
        &self,
        lever: Vector3<f64>,
        scale: (f64, f64),
        (shape, theta): &(ClockShape, Vec<f64>),
        steps: Steps,
    ) -> Option<Chosen> {
        let raw = pose_fit::profile(
            self.data,
            &self.profile_windows,
            lever,
            scale,
            &|t| shape.value(theta, t),
            (self.window_search(), WINDOW_SEARCH_S),
        );
        let profile = calibrated_profile(consistent_windows(raw), &self.profile_windows)?;
        Some(self.decide(profile, (lever, scale, theta[0]), steps))
    }

    /// How the profile's windows are searched: every window for a deeper root than the one it
    /// settled at, unless the whole mission's constant fit pins Δt within [`DEEP_SEARCH_SIGMA_S`]
    /// — windows that agree that well have none in another basin (a step or a first look without
    /// a lever leaves the constant's jackknife σ at 9–28 ms on the missions where a window hid
    /// one), and a long clean mission then pays nothing for the search.
    fn window_search(&self) -> WindowSearch {
        match &self.whole {
            Some(w) if w.theta_sigma[0] <= DEEP_SEARCH_SIGMA_S => WindowSearch::Failed,
            _ => WindowSearch::Every,
        }
    }

    /// The model chosen from `profile` (measured with `lever` held, at the mission's scale and
    /// the clock column's scale `scale`, its windows started from a clock whose first parameter is
    /// `clock_s`) and its parameters fitted with the lever over every window, σ by the jackknife
    /// over windows, at least the formal σ (the whole mission's fit when that is the constant).
    fn decide(
        &self,
        profile: OffsetProfile,
        (lever, scale, clock_s): (Vector3<f64>, (f64, f64), f64),
        steps: Steps,
    ) -> Chosen {
        let (offset0, whole_sigma) = match &self.whole {
            Some(w) => (w.theta[0], w.theta_sigma[0].max(POSE_SIGMA_FLOOR_S)),
            None => (clock_s, f64::INFINITY),
        };
        // A step's time on the positions, else on the speed signals.
        let locate = |d: (f64, f64), span: (f64, f64)| {
            pose_fit::locate_change(self.data, &lever, scale.0, d, span)
                .or_else(|| (self.signals)().and_then(|re| locate_change(re, d, span)))
        };
        let model = choose_model(
            &profile,
            (offset0, whole_sigma),
            Some(&locate),
            self.forced,
            steps,
        );
        let (next_shape, theta0) = shape_of(&model, offset0);
        let fit = match (&self.whole, model.model) {
            (Some(w), OffsetModel::Constant) => Some(w.clone()),
            _ => pose_fit::fit(
                self.data,
                &self.windows_of(&next_shape),
                next_shape.clone(),
                theta0,
                lever,
                true,
            )
            .filter(|f| f.converged),
        };
        Chosen {
            profile,
            model,
            shape: next_shape,
            fit,
            lever_m: lever,
        }
    }

    /// The windows a fit of `shape` uses: every one, less those holding a change of a piecewise
    /// clock (they mix two offsets).
    fn windows_of(&self, shape: &ClockShape) -> Vec<pose_fit::Window> {
        match shape {
            ClockShape::Piecewise { changes } => self
                .windows
                .iter()
                .filter(|w| !changes.iter().any(|&c| c > w.t_start && c < w.t_end))
                .cloned()
                .collect(),
            _ => self.windows.clone(),
        }
    }

    /// The clock when the chosen model's fit did not converge: its parameters are the windows'
    /// (a constant's the weighted mean of the `profile`), the lever the one they held. `None` when
    /// no lever was ever fitted (no whole-mission constant fit either).
    pub(super) fn without_fit(
        &self,
        profile: OffsetProfile,
        mut model: ClockModel,
        lever_m: Vector3<f64>,
    ) -> Option<PoseClock> {
        // No lever was ever fitted (neither the whole mission's constant nor the chosen model
        // converged): the windows held it at zero, and a forward lever then reads as Δt (0.2 m at a
        // walk is half a second) with a σ that cannot show it. The signal searches' answer stands.
        self.whole.as_ref()?;
        if model.model == OffsetModel::Constant {
            if let Some((mean, sigma)) =
                windows_offset_s(&profile, (f64::NEG_INFINITY, f64::INFINITY))
            {
                model.offset_s = mean;
                model.sigma_s = sigma;
            }
        }
        model.describe();
        Some(PoseClock {
            outlier_windows: 0,
            sigma_parts: None,
            first_offset: (model.offset_s, model.sigma_s),
            fit: None,
            profile,
            model,
            lever: (lever_m, None),
            replaced: None,
            beyond_lever: None,
        })
    }

    /// The fit to report for `model`, whose fit is `last`: a drift is declared only when the fitted
    /// drift exceeds the resolution of the windows (the drift their calibrated σ can tell from a
    /// constant clock); below it the data do not refute the constant, whatever the windows' BIC
    /// said (receipt-stamp latencies or a gait tilt a few windows), and the model becomes the whole
    /// mission's constant. So too a step: kept only where the final fit tells some two neighbouring
    /// segments apart ([`steps_resolved`]); otherwise the model is the whole mission's constant, or
    /// where there was none (the fit from the signal searches' answer went to another basin) the
    /// constant fitted from the segments' mean with their lever (where that fit does not converge,
    /// the steps stand). A profile measured in another basin than the fit's (a walking robot's
    /// windows with the lever held, where Δt trades against it) can slope across the mission and
    /// propose a step whose two sides the fit then finds 6 ms apart under σ of 14–40 ms: not a
    /// clock event. Never when the model was forced.
    pub(super) fn resolved(&self, model: &mut ClockModel, last: PoseFit) -> PoseFit {
        if let (None, OffsetModel::Piecewise) = (self.forced, model.model) {
            if !steps_resolved(&last) {
                let constant = self.whole.clone().or_else(|| {
                    let mean = last.theta.iter().sum::<f64>() / last.theta.len() as f64;
                    pose_fit::fit(
                        self.data,
                        &self.windows,
                        ClockShape::Constant,
                        vec![mean],
                        last.lever_m,
                        true,
                    )
                    .filter(|f| f.converged)
                });
                if let Some(w) = constant {
                    model.model = OffsetModel::Constant;
                    model.segments.clear();
                    model.criterion = format!(
                        "{}; the fit does not tell the segments apart (each step within {STEP_RESOLUTION_Z} σ)",
                        model.criterion
                    );
                    return w;
                }
            }
        }
        if self.forced.is_none() && model.model == OffsetModel::Linear {
            let fitted_ppm = -last.theta[1] * 1e6;
            if let (Some(resolution), Some(w)) = (model.drift_resolution_ppm, &self.whole) {
                if fitted_ppm.abs() < resolution {
                    model.model = OffsetModel::Constant;
                    model.criterion = format!(
                        "{}; the fitted drift {fitted_ppm:+.1} ppm is below the resolution {resolution:.1} ppm",
                        model.criterion
                    );
                    return w.clone();
                }
            }
        }
        last
    }
}

/// The clock shape of `model` and its parameters to start from.
fn shape_of(model: &ClockModel, offset0: f64) -> (ClockShape, Vec<f64>) {
    match model.model {
        OffsetModel::Constant => (ClockShape::Constant, vec![offset0]),
        OffsetModel::Linear => (
            ClockShape::Linear { t_mid: model.t_mid },
            vec![model.offset_s, -model.drift_ppm.unwrap_or(0.0) * 1e-6],
        ),
        OffsetModel::Piecewise => (
            ClockShape::Piecewise {
                changes: model.segments.iter().skip(1).map(|s| s.t_start).collect(),
            },
            model.segments.iter().map(|s| s.offset_s).collect(),
        ),
    }
}

//! What the offset search is asked: which signal it correlates ([`OffsetMethod`]) and how far and
//! how finely it searches ([`OffsetParams`]). They sit below the signals and the search that both
//! read them (`crate::align::signals`, `crate::align::time_offset`, which re-exports them), so
//! neither has to reach up into the other.

use crate::align::curvature::CurvatureParams;
use crate::align::xcorr::Centering;

/// Which signal the offset is estimated from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OffsetMethod {
    /// The curvature signature of eq. (1), unsigned, eq. (2) NCC (the paper's method).
    Curvature,
    /// The windowed speed profile (the baseline; blind at constant speed).
    Speed,
    /// The signed curvature in the horizontal plane (counter-clockwise positive), mean-removed NCC:
    /// a turn left and a turn right no longer look alike, and noise averages to zero instead of
    /// correlating positively as unsigned κ does.
    #[serde(rename = "signed-curvature")]
    SignedCurvature,
    /// Runs `speed`, `signed-curvature` and `curvature` and applies a consistent, confident answer
    /// (see [`crate::align::auto_offset`]).
    Auto,
    /// The positions themselves, with the estimate's body-frame lever fitted (needs the estimate's
    /// orientation; see [`crate::align::pose_fit`]): `auto` refines its answer with it.
    Pose,
}

impl OffsetMethod {
    /// The method's name as on the command line and in reports.
    pub fn as_str(&self) -> &'static str {
        match self {
            OffsetMethod::Curvature => "curvature",
            OffsetMethod::Speed => "speed",
            OffsetMethod::SignedCurvature => "signed-curvature",
            OffsetMethod::Auto => "auto",
            OffsetMethod::Pose => "pose",
        }
    }

    /// Whether the method's NCC removes the means over the overlap: signed curvature always, speed
    /// when `params` say so, the paper's unsigned curvature never (eq. 2).
    pub fn centering(&self, params: &OffsetParams) -> Centering {
        match self {
            OffsetMethod::Speed if params.speed_mean_removed => Centering::MeanRemoved,
            OffsetMethod::SignedCurvature | OffsetMethod::Auto | OffsetMethod::Pose => {
                Centering::MeanRemoved
            }
            _ => Centering::Raw,
        }
    }
}

impl std::fmt::Display for OffsetMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

/// Parameters of the offset search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OffsetParams {
    /// The largest |Δt| searched, seconds.
    pub max_offset_s: f64,
    /// The fine grid step δt, seconds.
    pub grid_s: f64,
    /// The coarse grid step of the full-range FFT search, seconds.
    pub coarse_grid_s: f64,
    /// Parameters of eq. (1); `dt_max_s` (Δt_max) is also the largest gap interpolated across on the
    /// grid, for both methods.
    pub curvature: CurvatureParams,
    /// Window of the speed profile, seconds (see [`crate::align::speed`]).
    pub speed_window_s: f64,
    /// Whether the `speed` NCC removes the mean over the overlap (Pearson). The curvature NCC is
    /// always eq. (2), not mean-removed; the signed curvature's always is.
    pub speed_mean_removed: bool,
    /// The largest gap interpolated across on the grid and bridged by a speed chord, seconds;
    /// `None`: `curvature.dt_max_s` (a long Δt_max for slow robots should not bridge an outage).
    pub max_gap_s: Option<f64>,
}

/// The coarse grid step of the full-range FFT search, seconds (the fine grid is at most this).
pub const COARSE_GRID_S: f64 = 0.02;

impl Default for OffsetParams {
    fn default() -> Self {
        OffsetParams {
            max_offset_s: 30.0,
            grid_s: 0.001,
            coarse_grid_s: COARSE_GRID_S,
            curvature: CurvatureParams::default(),
            speed_window_s: 2.0,
            speed_mean_removed: true,
            max_gap_s: None,
        }
    }
}

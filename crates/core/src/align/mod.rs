//! Time alignment: find the clock offset Δt between an estimate and its reference from positions alone.

pub mod auto_offset;
pub mod auto_params;
pub mod clock_model;
pub mod curvature;
pub(crate) mod fine_sums;
pub mod grid;
pub mod jumps;
pub mod offset_params;
pub mod offset_profile;
pub(crate) mod offset_sigma;
pub mod pose_fit;
pub mod pose_model;
pub(crate) mod signals;
pub mod speed;
pub(crate) mod still;
pub mod time_offset;
pub mod xcorr;

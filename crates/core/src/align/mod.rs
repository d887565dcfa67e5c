//! Time alignment: find the clock offset Δt between an estimate and its reference from positions alone.

pub mod auto_offset;
pub mod auto_params;
pub mod clock_model;
pub mod curvature;
pub mod fine_sums;
pub mod grid;
pub mod offset_profile;
pub mod offset_sigma;
pub mod signals;
pub mod speed;
pub mod still;
pub mod time_offset;
pub mod xcorr;

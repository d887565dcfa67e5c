//! Metrics: Drift Error (the paper) and, in [`standard`], evo's APE/RPE.

pub(crate) mod decimate;
pub mod drift_error;
pub mod lever;
pub mod lever_fit;
pub(crate) mod rotation_in_place;
pub mod standard;
pub(crate) mod windows;

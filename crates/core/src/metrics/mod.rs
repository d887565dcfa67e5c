//! Metrics: Drift Error (the paper) and, in [`standard`], evo's APE/RPE.

pub mod decimate;
pub mod drift_error;
pub mod lever;
pub mod lever_fit;
pub mod rotation_in_place;
pub mod standard;
pub mod windows;

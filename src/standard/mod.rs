//! Command-level code of the standard metrics: the inputs of `trajdrift ape`/`rpe` (evo's positional
//! forms mapped onto trajdrift's readers) and `trajdrift offset` (every offset method side by side).
//! The metrics themselves are in the core crate (`trajdrift_core::metrics::standard`).

pub mod inputs;
pub mod offsets;

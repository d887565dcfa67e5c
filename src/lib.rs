//! trajdrift: evaluate robot trajectories from positions alone.
//!
//! This crate is the application: the evaluation of a request ([`eval`]), annotated copies of
//! recordings ([`annotate`]), batches of missions ([`batch`]), figures ([`plot`]) and the command line.
//! Everything below it — readers, trajectories, the time alignment, the metrics, the report types — is the
//! core crate [`trajdrift_core`], re-exported here.

pub use trajdrift_core::{
    align, clock, decode, diag, error, metrics, output, params, report, simulate, sources, stats,
    trajectory,
};
pub use trajdrift_core::{Error, Result, Trajectory};

extern crate self as trajdrift;

pub mod annotate;
pub mod batch;
pub mod cli;
pub mod eval;
pub mod evo;
pub mod job;
pub mod plot;
pub mod render;
pub mod standard;

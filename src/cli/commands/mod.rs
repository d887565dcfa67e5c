//! One handler per command: turn arguments into a library call, print the result.

pub mod ape;
pub mod audit;
pub mod batch;
pub mod completions;
pub mod eval;
pub mod export;
pub mod man;
pub mod merge;
pub mod metric;
pub mod offset;
pub mod res;
pub mod restamp;
pub mod rpe;
pub mod simulate;
pub mod sweep;
pub mod topics;
pub mod traj;
pub mod validate;

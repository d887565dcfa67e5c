//! trajdrift: evaluate robot trajectories from positions alone.
//!
//! The pipeline reads like the folders: [`sources`] → [`decode`] → [`trajectory`] → [`align`] (time) →
//! [`metrics`] → [`report`]. The binary only parses arguments and prints.

pub mod align;
pub mod decode;
pub mod error;
pub mod eval;
pub mod metrics;
pub mod report;
pub mod simulate;
pub mod sources;
pub mod trajectory;

pub use error::{Error, Result};
pub use trajectory::Trajectory;
pub mod annotate;
pub mod batch;
pub mod plot;

//! trajdrift's core: everything that turns recorded positions into numbers, with no command line and
//! no figures.
//!
//! The layers, bottom to top: [`error`] and [`diag`] (what goes wrong, what the user must see) →
//! [`decode`] (message bytes → samples) → [`trajectory`] → [`sources`] (recordings and text files →
//! trajectories) → [`align`] (the clock offset and its model) → [`metrics`] (Drift Error, evo's APE and
//! RPE) → [`report`] (the typed result, serialised as the JSON report) and [`clock`] (the one clock
//! correction every consumer applies). [`output`] writes files; [`simulate`] writes missions with a known
//! truth. The application crate `trajdrift` (evaluation orchestration, annotation, batches, figures, the
//! command line) stands on this one; nothing here imports it.

pub mod align;
pub mod clock;
pub mod decode;
pub mod diag;
pub mod error;
pub mod metrics;
pub mod output;
pub mod params;
pub mod report;
pub mod simulate;
pub mod sources;
pub mod stats;
pub mod trajectory;

pub use error::{Error, Result};
pub use trajectory::Trajectory;

//! trajdrift: evaluate robot trajectories from positions alone.
//!
//! The clock offset between a reference and an estimate from their curvature or speed signatures,
//! the clock's model over the mission (constant, drifting, stepping), the paper's Drift Error, and
//! evo's APE and RPE to evo's six decimals — from MCAP, ROS 1 bags, rosbag2 folders, multi-file
//! missions and text trajectories.
//!
//! # The API
//!
//! The names below are the whole API of this crate (see [`api`] for the functions and their
//! options); the modules behind them are private and may move. [`read`] a trajectory from anything the
//! command line reads; [`evaluate`] a request (what `trajdrift eval` does) or
//! [`evaluate_trajectories`] in memory; [`time_offset`], [`drift_error`], [`ape`] and [`rpe`] alone.
//! The result is the typed [`Report`], the same that `trajdrift eval --json` writes.
//! [`main_with_args`] runs the command line in process.
//!
//! ```
//! use trajdrift::{evaluate, EvalRequest, NamedInput, TimeOffsetStatus};
//!
//! let (config, _notes) = EvalRequest {
//!     recordings: vec!["fixtures/sim_ground/mission.mcap".into()],
//!     reference: Some(NamedInput::topic("/reference/position")),
//!     estimates: vec![NamedInput::topic("lio=/estimate/odom")],
//!     ..Default::default()
//! }
//! .config()?;
//! let report = evaluate(&config)?;
//! let lio = &report.estimates[0];
//! assert_eq!(lio.time_offset.status, TimeOffsetStatus::Ok);
//! let sigma_s = lio.time_offset.sigma_s.unwrap_or(f64::NAN);
//! println!("Δt = {:+.3} s ± {sigma_s:.3} s", lio.time_offset.applied_s);
//! # Ok::<(), trajdrift::Error>(())
//! ```
//!
//! # The crates
//!
//! This crate is the application: the evaluation's orchestration, annotated copies of recordings,
//! batches of missions, figures and the command line. Everything below it — readers, trajectories,
//! the time alignment, the metrics, the report types — is the core crate [`trajdrift_core`],
//! re-exported here by module for programs that need a piece of it. `ARCHITECTURE.md` has the map.

pub use trajdrift_core::{
    align, clock, decode, diag, error, metrics, output, params, report, simulate, sources, stats,
    trajectory,
};
pub use trajdrift_core::{Error, Result, Trajectory};

// The API for programs (the Python package stands on these names only): see [`api`].
pub use api::{
    ape, drift_error, error_message, evaluate, evaluate_trajectories, read, rpe, time_offset,
    Alignment, AlignmentReport, CsvMapping, DeltaReport, DeltaUnit, ErrorStats, EvalConfig,
    EvalRequest, LeverSpec, MetricOptions, MetricResult, NamedInput, NamedTrajectory,
    PairSelection, ParamSpec, Parameters, Pipeline, Plane, PoseRelation, Poses, ReadOptions,
    Rotations, StampSeconds, StampSource, StandardResult, SyncMethod, TextFormat, TextOptions,
    TrajectoryInput, TrajectoryRead, ValueKind, SPECS,
};
pub use audit::report::AuditReport;
/// The command line, in process: what the `trajdrift` binary runs (see [`cli::main_with_args`]).
pub use cli::main_with_args;
pub use trajdrift_core::diag::Warning;
pub use trajdrift_core::report::json::{
    DriftErrorReport, EstimateReport, MethodStatus, OffsetSource, Report, TimeOffsetReport,
    TimeOffsetStatus,
};
/// Grading the default evaluation against simulated missions with a known truth (`trajdrift validate`).
pub use validate::{
    calibration, evaluate_pair, run as validate_missions, run_scenario, Calibration, MissionGrade,
    ValidateOptions,
};

extern crate self as trajdrift;

mod annotate;
pub mod api;
mod audit;
mod batch;
pub mod cli;
mod eval;
mod evo;
#[cfg(feature = "fuzzing")]
#[doc(hidden)]
pub mod fuzzing;
mod job;
mod plot;
mod render;
mod standard;
mod validate;

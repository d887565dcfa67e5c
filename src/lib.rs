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

// The API for programs (the Python package stands on these names only): see [`api`].
pub use api::{
    ape, drift_error, error_message, evaluate, evaluate_trajectories, read, rpe, time_offset,
    Alignment, AlignmentReport, CsvMapping, DeltaReport, DeltaUnit, ErrorStats, EvalConfig,
    EvalRequest, LeverSpec, MetricOptions, MetricResult, NamedInput, NamedTrajectory,
    PairSelection, ParamSpec, Parameters, Pipeline, Plane, PoseRelation, Poses, ReadOptions,
    Rotations, StampSeconds, StampSource, StandardResult, SyncMethod, TextFormat, TextOptions,
    TrajectoryInput, TrajectoryRead, ValueKind, SPECS,
};
/// The command line, in process: what the `trajdrift` binary runs (see [`cli::main_with_args`]).
pub use cli::main_with_args;
pub use trajdrift_core::diag::Warning;
pub use trajdrift_core::report::json::{
    DriftErrorReport, EstimateReport, MethodStatus, OffsetSource, Report, TimeOffsetReport,
    TimeOffsetStatus,
};

extern crate self as trajdrift;

pub mod annotate;
pub mod api;
pub mod audit;
pub mod batch;
pub mod cli;
pub mod eval;
pub mod evo;
pub mod job;
pub mod plot;
pub mod render;
pub mod standard;

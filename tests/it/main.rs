//! The integration tests: one binary, one module per subject (as ripgrep's `tests/tests.rs`), and the
//! helpers they share in [`common`]. Run one subject with `cargo test --test it SUBJECT::`.

mod common;
mod hostile_support;
mod robust_support;

mod acceptance;
mod annotate;
mod audit;
mod batch;
mod batch_integrity;
mod bounds;
mod cli;
mod clock_consumers;
mod conformance;
mod drift_error;
mod evo_cli;
mod evo_reference;
mod export;
mod extrinsics;
mod fixtures;
mod hostile;
mod lever_fit;
mod man;
mod mcap_source;
mod missions;
mod names;
mod outputs;
mod parameters;
mod pictures;
mod presets;
mod recordings;
mod text_formats;
mod tf_chains;
mod throughput_results;
mod time_offset;
mod time_offset_auto;
mod time_offset_profile;
mod validate;

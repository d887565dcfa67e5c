//! `trajdrift batch`: many missions evaluated in parallel, each streamed like `eval`, with per-mission
//! results and a summary across missions; `--shard I/N` and `trajdrift merge` spread a batch over a
//! cluster.
//!
//! [`discover`] finds the missions of a folder, [`manifest`] reads what to run, [`run`] runs it, [`summary`] aggregates, [`shard`] splits.

pub mod audit;
pub mod discover;
pub mod identity;
pub mod manifest;
pub mod merge;
pub mod run;
pub mod shard;
pub mod summary;
pub mod summary_files;
pub mod summary_html;

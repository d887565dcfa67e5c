//! evo's command line beyond the metric: the result files of `--save_results`, the figures of `-p`,
//! `trajdrift res` (evo_res) and `trajdrift traj` (evo_traj). Command-level code: it reads the
//! standard metrics' results and the report layer's evo result format ([`crate::report::evo_zip`]) and
//! draws with [`crate::plot::evo`].

pub mod metric_result;
pub mod res;
pub mod runs;
pub mod table;
pub mod traj;

//! The report: the typed result of an evaluation, serialised as the JSON report (every parameter
//! beside the numbers), the escaping of names that came from files, and evo's result files
//! (`--save_results` zips of JSON and `.npy` arrays).

pub mod escape;
pub mod evo_zip;
pub mod json;
pub mod npy;

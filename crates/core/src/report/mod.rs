//! The report: the typed result of an evaluation, serialised as the JSON report (every parameter
//! beside the numbers), and the escaping of names that came from files.

pub mod escape;
pub mod json;

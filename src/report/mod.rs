//! Reports: the JSON report (machine-readable, every parameter beside the numbers), the text table, and
//! the safe writing of output files.

pub mod escape;
pub mod html;
pub mod json;
pub mod output;
pub mod table;

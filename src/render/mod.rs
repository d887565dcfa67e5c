//! Presentation of a report: the text table for a terminal and the self-contained HTML page.

pub mod html;
pub mod table;

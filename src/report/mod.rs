//! Reports: the JSON report and the text table.

//! Diagnostics: what an evaluation tells its user beside the numbers. A [`Warning`] is a finding the user
//! must see (the command line exits with code 3 when there is one); it lives here, below every layer that
//! raises one (readers, alignment, metrics), so none of them imports another to report.

/// A warning the user must see (the CLI exits with code 3 when there is one).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Warning {
    /// Stable machine-readable code, e.g. `truncated_recording`.
    pub code: String,
    pub message: String,
}

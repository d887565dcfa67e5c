//! Diagnostics: what an evaluation tells its user beside the numbers. A [`Warning`] is a finding the user
//! must see (the command line exits with code 3 when there is one); it lives here, below every layer that
//! raises one (readers, alignment, metrics), so none of them imports another to report.

/// What a warning is about: a stable machine-readable code (its serde name is the JSON report's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WarningCode {
    /// A recording ends inside a record (cut short while written or copied).
    TruncatedRecording,
    /// A recording holds no channel at all.
    EmptyRecording,
    /// No time-offset method found a confident peak; none was applied.
    WeakTimeOffset,
    /// The clock offset drifts (a linear model was chosen from the data and applied).
    ClockDriftSuspected,
    /// The clock offset steps (a piecewise model was chosen from the data and applied).
    ClockStepSuspected,
    /// The curvature methods lead the speed method as a sensor mounted ahead of the other would.
    LeverArmSuspected,
    /// The methods disagreed and the lever-arm explanation could not be checked.
    LeverArmUnchecked,
    /// A walking robot's pose fit left out a fit that fits the windows better but needs a longer
    /// forward lever than its lead search allows for (right only where the sensors sit that far
    /// apart, and then the levers are to be given).
    LongLeverLeftOut,
    /// An audit's pairwise clock offsets do not add up around a triple of sources (closure).
    ClockClosureFailed,
}

impl WarningCode {
    /// The code as written in reports and on the terminal.
    pub fn as_str(self) -> &'static str {
        match self {
            WarningCode::TruncatedRecording => "truncated_recording",
            WarningCode::EmptyRecording => "empty_recording",
            WarningCode::WeakTimeOffset => "weak_time_offset",
            WarningCode::ClockDriftSuspected => "clock_drift_suspected",
            WarningCode::ClockStepSuspected => "clock_step_suspected",
            WarningCode::LeverArmSuspected => "lever_arm_suspected",
            WarningCode::LeverArmUnchecked => "lever_arm_unchecked",
            WarningCode::LongLeverLeftOut => "long_lever_left_out",
            WarningCode::ClockClosureFailed => "clock_closure_failed",
        }
    }

    /// The signal searches' lever warnings (`lever_arm_suspected`, `lever_arm_unchecked`): moot once
    /// the lever is measured (by the pose fit, or by the audit's lever report).
    pub fn is_lever(self) -> bool {
        matches!(
            self,
            WarningCode::LeverArmSuspected | WarningCode::LeverArmUnchecked
        )
    }
}

impl std::fmt::Display for WarningCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

/// A warning the user must see (the CLI exits with code 3 when there is one).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Warning {
    pub code: WarningCode,
    pub message: String,
}

impl Warning {
    /// A warning of `code` saying `message`.
    pub fn new(code: WarningCode, message: impl Into<String>) -> Warning {
        Warning {
            code,
            message: message.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_serialise_as_their_words() {
        for c in [
            WarningCode::TruncatedRecording,
            WarningCode::EmptyRecording,
            WarningCode::WeakTimeOffset,
            WarningCode::ClockDriftSuspected,
            WarningCode::ClockStepSuspected,
            WarningCode::LeverArmSuspected,
            WarningCode::LeverArmUnchecked,
            WarningCode::LongLeverLeftOut,
            WarningCode::ClockClosureFailed,
        ] {
            assert_eq!(
                serde_json::to_string(&c).unwrap(),
                format!("\"{}\"", c.as_str())
            );
        }
    }
}

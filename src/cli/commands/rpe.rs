//! `trajdrift rpe`: relative pose error with evo's command line and numbers (pairs from the estimate by
//! default; `-u m` restarts the path length after each pair).

use anyhow::Result;

use trajdrift::metrics::standard::{DeltaUnit, Metric, PairSelection};

use crate::cli::args::RpeArgs;

/// Runs the command; returns the exit code.
pub fn run(a: RpeArgs) -> Result<u8> {
    use trajdrift::params::{Bound, Range};
    Range {
        min: Bound::Exclusive(0.0),
        max: Bound::Inclusive(1.0e9),
        unit: "",
    }
    .check("--delta", a.delta)?;
    if a.delta_unit == "f" && a.delta.fract() != 0.0 {
        return Err(trajdrift::Error::InvalidArgument(format!(
            "--delta {}: with --delta_unit f it counts frames: give a whole number",
            a.delta
        ))
        .into());
    }
    Range {
        min: Bound::Inclusive(0.0),
        max: Bound::Inclusive(1.0),
        unit: "",
    }
    .check("--delta_tol", a.delta_tol)?;
    let sel = PairSelection {
        delta: a.delta,
        unit: DeltaUnit::parse(&a.delta_unit)?,
        rel_tol: a.delta_tol,
        all_pairs: a.all_pairs,
        from_reference: a.pairs_from_reference,
    };
    super::metric::run(&a.common, &a.evo, Metric::Rpe(sel))
}

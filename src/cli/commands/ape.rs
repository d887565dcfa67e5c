//! `trajdrift ape`: absolute pose error with evo's command line and numbers.

use anyhow::Result;

use trajdrift::metrics::standard::Metric;

use crate::cli::args::ApeArgs;

/// Runs the command; returns the exit code.
pub fn run(a: ApeArgs) -> Result<u8> {
    super::metric::run(&a.common, &a.evo, Metric::Ape)
}

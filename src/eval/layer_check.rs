//! A layer of parameters (a preset's `[parameters]`, a manifest's `[defaults]` or
//! `[mission.parameters]`, the command line's flags) checked on its own when it is read, so that a
//! value out of range is refused at load time — a usage error, exit 2, before any mission runs —
//! naming where it was written and the parameter as written there (`max_offset` in a manifest,
//! `--max-offset` on the command line).

use crate::error::{Error, Result};
use crate::params::Parameters;

/// How a layer names its parameters in messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Naming {
    /// Command-line flags: `--max-offset`.
    Flags,
    /// Manifest and preset keys: `max_offset`.
    Keys,
}

/// Checks `layer` alone; the refusal says `where_` it was written and names the parameter as
/// `naming` says.
pub fn check_layer(layer: &Parameters, where_: &str, naming: Naming) -> Result<()> {
    let checked = match naming {
        Naming::Flags => layer.validate(),
        Naming::Keys => layer.validate_as(&|key| key.to_string()),
    };
    checked.map_err(|e| refusal(where_, &e))
}

/// `e` as a usage error said at `where_`.
pub fn refusal(where_: &str, e: &Error) -> Error {
    Error::InvalidArgument(format!("{where_}: {e}"))
}

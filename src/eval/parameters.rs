//! The evaluation parameters on the command line. The parameters themselves are defined once, in the
//! core's table (`trajdrift_core::params`): key, type, help, default and range. This module only turns
//! that table into clap arguments ([`ParameterFlags`], flattened into `eval`, `batch` and `sweep`), so
//! a parameter added to the table is a flag with its help and default without a line here.

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};

pub use crate::params::{Parameters, Word};
use crate::params::{ValueKind, SPECS};

/// The heading the parameters stand under in `--help`.
pub const HEADING: &str = "Evaluation parameters (also manifest and preset keys, `-` written `_`)";

/// Every evaluation parameter as command-line flags: clap's view of [`Parameters`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParameterFlags(pub Parameters);

fn number(s: &str) -> Result<String, String> {
    s.trim()
        .parse::<f64>()
        .map(|_| s.to_string())
        .map_err(|e| e.to_string())
}

fn triple_text(s: &str) -> Result<String, String> {
    crate::params::triple(s).map(|_| s.to_string())
}

/// The clap argument of one parameter of the table.
fn arg(spec: &'static crate::params::ParamSpec) -> Arg {
    let arg = Arg::new(spec.key)
        .long(spec.flag().trim_start_matches("--").to_string())
        .value_name(spec.value_name)
        .help(spec.help_with_default())
        .allow_hyphen_values(spec.takes_negative() || matches!(spec.kind, ValueKind::Triple));
    match spec.kind {
        ValueKind::Number => arg.action(ArgAction::Set).value_parser(number),
        ValueKind::Triple => arg.action(ArgAction::Set).value_parser(triple_text),
        ValueKind::Numbers => arg
            .action(ArgAction::Append)
            .value_delimiter(',')
            .value_parser(number),
        ValueKind::Word(words) => arg
            .action(ArgAction::Set)
            .value_parser(PossibleValuesParser::new(words())),
        ValueKind::Words(words) => arg
            .action(ArgAction::Append)
            .value_delimiter(',')
            .value_parser(PossibleValuesParser::new(words())),
    }
}

impl Args for ParameterFlags {
    fn augment_args(cmd: Command) -> Command {
        SPECS
            .iter()
            .fold(cmd.next_help_heading(HEADING), |cmd, spec| {
                cmd.arg(arg(spec))
            })
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for ParameterFlags {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        Parameters::from_flags(|key| {
            m.get_many::<String>(key)
                .map(|values| values.cloned().collect())
        })
        .map(ParameterFlags)
        .map_err(|e| clap::Error::raw(clap::error::ErrorKind::ValueValidation, e))
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        let given = Self::from_arg_matches(m)?;
        self.0 = given.0.over(std::mem::take(&mut self.0));
        Ok(())
    }
}

/// clap's parser for a [`Word`] (a flag outside the parameter table, e.g. `export --stamp`): the
/// possible values are listed in `--help` and in the error of a wrong one.
pub fn word<T: Word>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::words()).map(|w| T::from_word(&w).expect("a possible value"))
}

/// Parses a finite number above zero (clap's parser for durations and rates).
pub fn positive(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("takes a number above zero, got `{s}`")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_flags(flags: &[&str]) -> Parameters {
        let cmd = ParameterFlags::augment_args(Command::new("t").allow_negative_numbers(true));
        let m = cmd
            .try_get_matches_from(std::iter::once("t").chain(flags.iter().copied()))
            .unwrap();
        ParameterFlags::from_arg_matches(&m).unwrap().0
    }

    #[test]
    fn every_parameter_of_the_table_is_a_flag() {
        let cmd = ParameterFlags::augment_args(Command::new("t"));
        let ids: Vec<&str> = cmd.get_arguments().map(|a| a.get_id().as_str()).collect();
        let keys: Vec<&str> = SPECS.iter().map(|s| s.key).collect();
        assert_eq!(ids, keys);
    }

    #[test]
    fn flags_parse_like_toml() {
        let p = from_flags(&[
            "--offset-method",
            "signed-curvature",
            "--window",
            "5,10",
            "--time-offset",
            "-0.35",
            "--origin",
            "47,-8,400",
            "--metrics",
            "de,kitti",
        ]);
        let t: Parameters = toml::from_str(
            "offset_method = \"signed-curvature\"\nwindow = [5, 10]\ntime_offset = -0.35\norigin = [47, -8, 400]\nmetrics = [\"de\", \"kitti\"]",
        )
        .unwrap();
        assert_eq!(p, t);
    }

    #[test]
    fn a_wrong_word_is_a_usage_error_listing_the_words() {
        let cmd = ParameterFlags::augment_args(Command::new("t"));
        let e = cmd
            .try_get_matches_from(["t", "--offset-method", "fast"])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("auto, speed, signed-curvature, curvature"),
            "{e}"
        );
    }

    #[test]
    fn help_shows_each_default() {
        let mut cmd = ParameterFlags::augment_args(Command::new("t"));
        let help = cmd.render_long_help().to_string();
        assert!(help.contains("[default: 30]"), "{help}");
        assert!(help.contains("[default: de,ape,rpe]"), "{help}");
    }
}

//! `-c FILE` / `--config FILE` of `ape`, `rpe`, `res` and `traj`: evo's argument JSON
//! (`{"align": true, "plot_mode": "xy", "t_max_diff": 0.02}`, the names of evo's argparse
//! destinations), which wins over the command line as in evo's `merge_config`.
//!
//! The command line is parsed once with clap; every argument given is written back as a flag
//! (`--name value`), an argument the JSON names is replaced by the JSON's value (`true` gives the
//! switch, `false` or `null` removes it, a list gives several values), and the result is parsed
//! again: one definition of the flags (clap's), no second parser. Keys that are evo settings or
//! positional inputs are named once on stderr and otherwise ignored.

use std::ffi::OsString;

use clap::parser::ValueSource;
use clap::{ArgAction, CommandFactory};

use crate::cli::args::Cli;

/// The command line with `-c FILE`'s JSON merged in; unchanged when there is none (or the line does
/// not parse: clap then reports it).
pub fn expand(argv: Vec<OsString>) -> Vec<OsString> {
    match try_expand(&argv) {
        Ok(Some(v)) => v,
        Ok(None) => argv,
        Err(e) => {
            eprintln!("error: {}", crate::cli::message(&e));
            std::process::exit(crate::cli::exit_status(&e).code() as i32);
        }
    }
}

/// Reads the command line once with clap; when it runs `ape`, `rpe`, `res` or `traj` with `-c FILE`,
/// returns it rewritten: the arguments given ([`given_arguments`]) less those the JSON sets, then the
/// JSON's ([`config_arguments`]), then `-c FILE` itself; keys that name no flag are named once on
/// stderr.
fn try_expand(argv: &[OsString]) -> anyhow::Result<Option<Vec<OsString>>> {
    let cmd = Cli::command();
    let Ok(matches) = cmd.clone().try_get_matches_from(argv) else {
        return Ok(None);
    };
    let Some((name, sub)) = matches.subcommand() else {
        return Ok(None);
    };
    if !["ape", "rpe", "res", "traj"].contains(&name) {
        return Ok(None);
    }
    let Some(path) = sub.get_one::<std::path::PathBuf>("config").cloned() else {
        return Ok(None);
    };
    let config = read_config(&path)?;
    let sub_cmd = cmd
        .find_subcommand(name)
        .expect("the subcommand just parsed")
        .clone();
    let (mut positionals, mut options) = given_arguments(&sub_cmd, sub, &config);
    let notes = config_arguments(&sub_cmd, &config, &mut options);
    if !notes.is_empty() {
        eprintln!(
            "note: -c {}: {} not used here (evo settings or inputs); ignored",
            path.display(),
            notes.join(", ")
        );
    }
    positionals.sort_by_key(|p| p.0);
    let mut out: Vec<OsString> = vec![argv[0].clone(), name.into()];
    out.extend(positionals.into_iter().flat_map(|p| p.1));
    out.extend(options);
    // `-c FILE` stays on the line: the command names it to the output guard as an input.
    let mut config_flag = OsString::from("--config=");
    config_flag.push(&path);
    out.push(config_flag);
    Ok(Some(out))
}

/// The JSON object of `-c FILE`: a file that cannot be read, is not JSON or not an object is a
/// one-line error naming it.
fn read_config(
    path: &std::path::Path,
) -> anyhow::Result<serde_json::Map<String, serde_json::Value>> {
    let text = std::fs::read_to_string(path).map_err(|cause| trajdrift::Error::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        trajdrift::Error::InvalidArgument(format!(
            "-c {}: not JSON ({e}); expected evo's argument file {{\"flag\": value, ...}}",
            path.display()
        ))
    })?;
    let serde_json::Value::Object(config) = json else {
        return Err(trajdrift::Error::InvalidArgument(format!(
            "-c {}: expected a JSON object {{\"flag\": value, ...}}",
            path.display()
        ))
        .into());
    };
    Ok(config)
}

/// An option's flag as written on a command line: `--long`, else `-s`.
fn flag_of(a: &clap::Arg) -> OsString {
    match (a.get_long(), a.get_short()) {
        (Some(l), _) => format!("--{l}").into(),
        (None, Some(s)) => format!("-{s}").into(),
        _ => OsString::new(),
    }
}

/// The arguments given on the command line, written back as tokens, except `-c` itself and those
/// `config` sets: the positionals as (index, values) and the options as flags (`--name=value`, or
/// the flag and then its values when it took several).
fn given_arguments(
    sub_cmd: &clap::Command,
    sub: &clap::ArgMatches,
    config: &serde_json::Map<String, serde_json::Value>,
) -> (Vec<(usize, Vec<OsString>)>, Vec<OsString>) {
    let mut positionals: Vec<(usize, Vec<OsString>)> = Vec::new();
    let mut options: Vec<OsString> = Vec::new();
    for a in sub_cmd.get_arguments() {
        let id = a.get_id().as_str();
        if id == "config"
            || config.contains_key(id)
            || a.get_long().is_some_and(|l| config.contains_key(l))
        {
            continue;
        }
        if sub.value_source(id) != Some(ValueSource::CommandLine) {
            continue;
        }
        if a.is_positional() {
            let values: Vec<OsString> = sub
                .get_raw(id)
                .map(|v| v.map(OsString::from).collect())
                .unwrap_or_default();
            positionals.push((a.get_index().unwrap_or(0), values));
            continue;
        }
        match a.get_action() {
            ArgAction::SetTrue => {
                if sub.get_flag(id) {
                    options.push(flag_of(a));
                }
            }
            ArgAction::Count => {
                for _ in 0..sub.get_count(id) {
                    options.push(flag_of(a));
                }
            }
            _ => {
                for occurrence in sub.get_raw_occurrences(id).into_iter().flatten() {
                    let mut tok = flag_of(a);
                    let vals: Vec<&std::ffi::OsStr> = occurrence.collect();
                    if vals.len() == 1 {
                        tok.push("=");
                        tok.push(vals[0]);
                        options.push(tok);
                    } else {
                        options.push(tok);
                        options.extend(vals.iter().map(|v| OsString::from(*v)));
                    }
                }
            }
        }
    }
    (positionals, options)
}

/// Appends the JSON's keys to `options` as flags of `sub_cmd` (found by id or long name, `-` and `_`
/// alike): `true` the switch, `false`/`null` nothing, a list the flag and its values, anything else
/// `--name=value`. Returns the keys that name no option (evo settings, positional inputs).
fn config_arguments(
    sub_cmd: &clap::Command,
    config: &serde_json::Map<String, serde_json::Value>,
    options: &mut Vec<OsString>,
) -> Vec<String> {
    let find = |key: &str| {
        sub_cmd.get_arguments().find(|a| {
            a.get_id().as_str() == key
                || a.get_long() == Some(key)
                || a.get_long().map(|l| l.replace('-', "_")) == Some(key.replace('-', "_"))
        })
    };
    let scalar = |v: &serde_json::Value| match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    };
    let mut notes = Vec::new();
    for (key, value) in config {
        let Some(a) = find(key) else {
            notes.push(key.clone());
            continue;
        };
        if a.is_positional() || a.get_id() == "config" {
            notes.push(key.clone());
            continue;
        }
        match (a.get_action(), value) {
            (ArgAction::SetTrue | ArgAction::Count, serde_json::Value::Bool(true)) => {
                options.push(flag_of(a))
            }
            (_, serde_json::Value::Bool(false) | serde_json::Value::Null) => {}
            (_, serde_json::Value::Array(items)) => {
                options.push(flag_of(a));
                options.extend(items.iter().map(|v| OsString::from(scalar(v))));
            }
            (_, v) => {
                let mut tok = flag_of(a);
                tok.push("=");
                tok.push(scalar(v));
                options.push(tok);
            }
        }
    }
    notes
}

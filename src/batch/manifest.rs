//! The batch manifest: which missions to evaluate, each a recording, a reference, one or more named
//! estimates and optional parameter overrides, in TOML (read with the `toml` crate and serde):
//!
//! ```toml
//! [defaults]                 # optional, for every mission
//! window = [5, 10]
//! platform = "wheeled"
//!
//! [[mission]]
//! name = "lever_arm"         # optional: default the recording's file stem
//! recording = "fixtures/lever_arm/mission.mcap"   # relative to the manifest
//! reference = "/reference/position"
//! estimates = ["/estimate/odom", "pose=/estimate/pose"]
//! [mission.parameters]       # optional, over the defaults
//! time_offset = 0.2
//!
//! [[mission]]                # a preset names the topics (see presets/); reference/estimates
//! recording = "grandtour/2024-11-14.bag"          # given here replace the preset's
//! preset = "grandtour"       # or in [defaults]: preset = "grandtour"
//! ```
//!
//! With a preset, the recording's topic list is read when the manifest is loaded, so a recording
//! that lacks the preset's topics fails the batch before any mission runs.
//!
//! A folder of recordings is the same with one mission per `.mcap` found (see [`Manifest::from_dir`]).
//!
//! Parameters are layered in one order ([`Parameters::layered`]): the preset's `[parameters]` <
//! `[defaults]` < `[mission.parameters]` < the command line's flags.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::eval::config::{EvalConfig, NamedInput};
use crate::eval::layer_check::{check_layer, refusal, Naming};
use crate::eval::parameters::Parameters;
use crate::eval::preset::Preset;

/// The largest manifest read (ten thousand missions take about 2 MB).
pub const MAX_MANIFEST_BYTES: u64 = 16 << 20;

/// One mission as written in the manifest.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mission {
    /// Unique name: the output files are `<name>.json` and `<name>.mcap`.
    pub name: Option<String>,
    pub recording: PathBuf,
    /// Needed unless a preset names it.
    pub reference: Option<String>,
    /// `[NAME=]TOPIC`, like `eval --estimate`; empty: the preset's.
    #[serde(default)]
    pub estimates: Vec<String>,
    /// A built-in preset, or a preset file relative to the manifest.
    pub preset: Option<String>,
    /// Evaluation parameters over `[defaults]`, and optionally `preset`.
    #[serde(default)]
    pub parameters: toml::Table,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    /// Evaluation parameters for every mission, and optionally `preset`.
    #[serde(default)]
    defaults: toml::Table,
    #[serde(default)]
    mission: Vec<Mission>,
}

/// A manifest's parameter table: the evaluation parameters and, beside them, an optional `preset`
/// (which topics to take; not a parameter).
fn split_table(mut t: toml::Table, what: &str) -> Result<(Option<String>, Parameters)> {
    let preset = match t.remove("preset") {
        Some(toml::Value::String(s)) => Some(s),
        Some(other) => {
            return Err(Error::InvalidArgument(format!(
                "{what}: preset = {other}: expected a preset name or file"
            )))
        }
        None => None,
    };
    let parameters = t.try_into::<Parameters>().map_err(|e| {
        Error::InvalidArgument(format!(
            "{what}: {}",
            e.to_string()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ")
        ))
    })?;
    Ok((preset, parameters))
}

/// What a folder of recordings runs: the same inputs and parameters for every mission.
#[derive(Debug, Clone, Default)]
pub struct FolderRequest {
    pub reference: Option<String>,
    /// `[NAME=]TOPIC`; empty: the preset's.
    pub estimates: Vec<String>,
    pub preset: Option<String>,
    pub parameters: Parameters,
}

/// A mission ready to run: its name and its evaluation request.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionSpec {
    pub name: String,
    pub config: EvalConfig,
}

/// Every mission of a batch, in manifest order, names unique.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Manifest {
    pub missions: Vec<MissionSpec>,
}

/// True for names usable as file names everywhere: letters, digits, `.`, `_`, `-`, not starting with
/// `.`, at most 200 characters (`<name>_figures` and the temporary files stay under the 255 bytes a
/// file name may have).
pub fn valid_name(n: &str) -> bool {
    !n.is_empty()
        && n.len() <= 200
        && !n.starts_with('.')
        && n.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'))
}

impl Manifest {
    /// Reads a TOML manifest; relative recording paths are relative to its folder. `cli`: the
    /// command line's parameters, over every mission's.
    pub fn from_toml(path: &Path, cli: &Parameters) -> Result<Manifest> {
        check_layer(cli, "the command line", Naming::Flags)?;
        let text = crate::sources::input::read_text_bounded(path, MAX_MANIFEST_BYTES, "manifest")?;
        let file: File = toml::from_str(&text).map_err(|e| {
            Error::InvalidArgument(format!(
                "{}: not a valid manifest: {}",
                path.display(),
                e.to_string().replace('\n', " ")
            ))
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        let origin = path.display().to_string();
        let (default_preset, defaults) =
            split_table(file.defaults, &format!("{origin}: [defaults]"))?;
        check_layer(&defaults, &format!("{origin}: [defaults]"), Naming::Keys)?;
        let mut missions = Vec::with_capacity(file.mission.len());
        for m in file.mission {
            let recording = base.join(&m.recording);
            let name = m.name.clone().unwrap_or_else(|| stem(&m.recording));
            let shown = crate::report::escape::escape(&name).into_owned();
            let reference = m.reference.as_deref().map(NamedInput::topic);
            let estimates: Vec<NamedInput> =
                m.estimates.iter().map(|e| NamedInput::topic(e)).collect();
            let where_ = format!("{origin}: mission {shown}: [mission.parameters]");
            let (mission_preset, own) = split_table(m.parameters, &where_)?;
            check_layer(&own, &where_, Naming::Keys)?;
            let preset = m.preset.or(mission_preset).or(default_preset.clone());
            let config = mission_config(
                recording,
                reference,
                estimates,
                preset.as_deref().map(|p| (p, base)),
                &[&defaults, &own, cli],
                Naming::Keys,
            )
            .map_err(|e| refusal(&format!("{origin}: mission {shown}"), &e))?;
            missions.push(MissionSpec { name, config });
        }
        let manifest = Manifest { missions };
        manifest.check(&path.display().to_string())?;
        Ok(manifest)
    }

    /// One mission per recording found in `dir` by [`super::discover::missions_in`] (`.mcap` and
    /// `.bag` files, rosbag2 folders, and mission folders of bags one level down), named by its path
    /// under `dir` (`runs/a.mcap` → `runs-a`), sorted by name; each evaluated as `request` says.
    pub fn from_dir(dir: &Path, request: &FolderRequest) -> Result<Manifest> {
        let missions = super::discover::missions_in(dir)?
            .into_iter()
            .map(|m| {
                let name = m.name;
                let config = mission_config(
                    m.recording,
                    request.reference.as_deref().map(NamedInput::topic),
                    request
                        .estimates
                        .iter()
                        .map(|e| NamedInput::topic(e))
                        .collect(),
                    request.preset.as_deref().map(|s| (s, Path::new("."))),
                    &[&request.parameters],
                    Naming::Flags,
                )
                .map_err(|e| refusal(&format!("{}: mission {name}", dir.display()), &e))?;
                Ok(MissionSpec { name, config })
            })
            .collect::<Result<Vec<_>>>()?;
        let manifest = Manifest { missions };
        manifest.check(&dir.display().to_string())?;
        Ok(manifest)
    }

    fn check(&self, origin: &str) -> Result<()> {
        if self.missions.is_empty() {
            return Err(Error::InvalidArgument(format!(
                "{origin}: no mission (add [[mission]] entries, or recordings to the folder: .mcap, .bag, rosbag2 folders, mission folders of bags)"
            )));
        }
        let mut names: Vec<&str> = Vec::new();
        for m in &self.missions {
            if !valid_name(&m.name) {
                return Err(Error::InvalidArgument(format!(
                    "{origin}: mission name `{}`: use letters, digits, `.`, `_` and `-` only, not starting with `.`, at most 200",
                    crate::report::escape::escape(&m.name)
                )));
            }
            if names.contains(&m.name.as_str()) {
                return Err(Error::InvalidArgument(format!(
                    "{origin}: two missions are named `{}`; give each a unique name",
                    m.name
                )));
            }
            names.push(&m.name);
        }
        Ok(())
    }
}

/// One mission's request: its inputs (named, or picked by a preset loaded relative to its base
/// folder) and its parameters, `layers` over the preset's from the lowest to the highest.
fn mission_config(
    recording: PathBuf,
    reference: Option<NamedInput>,
    estimates: Vec<NamedInput>,
    preset: Option<(&str, &Path)>,
    layers: &[&Parameters],
    naming: Naming,
) -> Result<EvalConfig> {
    let preset = preset
        .map(|(spec, base)| Preset::load_from(spec, base))
        .transpose()?;
    let recordings = [recording];
    let config = crate::eval::roles::resolve(
        &recordings,
        reference,
        estimates,
        preset.as_ref(),
        "give a reference (reference = \"TOPIC\" or --reference) or a preset",
    )?
    .config(&recordings, layers);
    // Every value is checked now, not when the mission runs: a manifest's mistake is a usage error
    // before any mission starts, naming the key (a combination of layers, e.g. t_start after t_end).
    if naming == Naming::Keys {
        config.params.validate_as(&|key| key.to_string())?;
    }
    config.validate()?;
    Ok(config)
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::config::Platform;

    #[test]
    fn parses_defaults_and_overrides() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.toml");
        std::fs::write(
            &p,
            r#"
[defaults]
window = [5, 10]
platform = "wheeled"

[[mission]]
recording = "a/mission.mcap"
reference = "/reference/position"
estimates = ["/estimate/odom", "pose=/estimate/pose"]

[[mission]]
name = "b"
recording = "b.mcap"
reference = "/r"
estimates = ["/e"]
[mission.parameters]
time_offset = -0.25
window = [2]
"#,
        )
        .unwrap();
        let m = Manifest::from_toml(&p, &Parameters::default()).unwrap();
        assert_eq!(m.missions[0].name, "mission");
        assert_eq!(m.missions[0].config.params.windows_m(), vec![5.0, 10.0]);
        assert_eq!(m.missions[0].config.estimates[1].name, "pose");
        assert_eq!(m.missions[1].config.params.time_offset, Some(-0.25));
        assert_eq!(m.missions[1].config.params.windows_m(), vec![2.0]);
        assert_eq!(m.missions[1].config.params.platform(), Platform::Wheeled);
        assert_eq!(
            m.missions[0].config.recording.as_deref(),
            Some(dir.path().join("a/mission.mcap").as_path())
        );
    }

    #[test]
    fn rejects_unknown_fields_and_duplicate_names() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.toml");
        std::fs::write(&p, "[[mission]]\nrecording = \"a.mcap\"\nreference = \"/r\"\nestimates = [\"/e\"]\nwindows = [1]\n").unwrap();
        let e = Manifest::from_toml(&p, &Parameters::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("windows"), "{e}");
        std::fs::write(&p, "[[mission]]\nrecording = \"a.mcap\"\nreference = \"/r\"\nestimates = [\"/e\"]\n[[mission]]\nrecording = \"x/a.mcap\"\nreference = \"/r\"\nestimates = [\"/e\"]\n").unwrap();
        let e = Manifest::from_toml(&p, &Parameters::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("two missions"), "{e}");
    }
}

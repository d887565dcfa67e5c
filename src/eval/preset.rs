//! Presets: the usual reference and estimate topics of a dataset (GrandTour, FoMo), so that
//! `--preset grandtour` replaces three topic flags, and `trajdrift topics` can say which dataset a
//! recording looks like.
//!
//! A preset is a TOML file (the format is documented at the top of each file in `presets/`). The
//! built-in ones are compiled into the binary (`include_str!`), so they work from any folder; a user's
//! copy is passed by path. Each role lists alternative topics (GrandTour's older bags say `/gt_box`
//! where newer ones say `/boxi`): the first one present in the recording wins.

use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::eval::config::NamedInput;
use crate::eval::parameters::Parameters;
use crate::sources::TopicInfo;

/// The built-in presets: name and TOML text.
pub const BUILTIN: [(&str, &str); 3] = [
    ("grandtour", include_str!("../../presets/grandtour.toml")),
    (
        "grandtour-prism",
        include_str!("../../presets/grandtour-prism.toml"),
    ),
    ("fomo", include_str!("../../presets/fomo.toml")),
];

/// The largest preset file read (the built-in ones are under 4 KiB).
pub const MAX_PRESET_BYTES: u64 = 1 << 20;

/// The reference of a preset: alternative topics, and what to tell the user when none is present.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Alternatives, first present wins; empty when the reference is a file (`--reference-file`).
    #[serde(default)]
    pub topics: Vec<String>,
    /// What to do when the recording has none of them.
    pub note: Option<String>,
}

/// One estimate of a preset.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimateSpec {
    /// The estimate's name in the report.
    pub name: String,
    /// Alternatives, first present wins.
    pub topics: Vec<String>,
}

/// A preset as written in its TOML file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preset {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// `legged` or `wheeled`: a hint for people (the evaluation's platform is set by `parameters`).
    pub robot: Option<String>,
    #[serde(default)]
    pub reference: ReferenceSpec,
    #[serde(default, rename = "estimate")]
    pub estimates: Vec<EstimateSpec>,
    /// Defaults under the command line's flags.
    #[serde(default)]
    pub parameters: Parameters,
}

/// The inputs a preset picks in one recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    pub reference: NamedInput,
    pub estimates: Vec<NamedInput>,
    /// Names of the preset's estimates absent from the recording (skipped).
    pub skipped: Vec<String>,
}

/// The first of `alternatives` present in `topics`.
fn first_present<'a>(alternatives: &'a [String], topics: &[TopicInfo]) -> Option<&'a String> {
    alternatives
        .iter()
        .find(|a| topics.iter().any(|t| &t.topic == *a))
}

/// The names `--preset` knows.
pub fn known() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// The built-in presets whose topics a recording has (its reference, when the preset names one,
/// and at least one estimate), for `trajdrift topics`.
pub fn matching(topics: &[TopicInfo]) -> Vec<String> {
    BUILTIN
        .iter()
        .filter_map(|(name, text)| Preset::parse(text, name).ok())
        .filter(|p| p.matches(topics))
        .map(|p| p.name)
        .collect()
}

impl Preset {
    /// Parses a preset's TOML text; `origin` (a name or a path) goes into the error.
    pub fn parse(text: &str, origin: &str) -> Result<Preset> {
        let p: Preset = toml::from_str(text).map_err(|e| {
            Error::InvalidArgument(format!(
                "{origin}: not a valid preset: {}",
                e.to_string()
                    .split_whitespace()
                    .collect::<Vec<_>>()
                    .join(" ")
            ))
        })?;
        if p.estimates.is_empty() || p.estimates.iter().any(|e| e.topics.is_empty()) {
            return Err(Error::InvalidArgument(format!(
                "{origin}: a preset needs at least one [[estimate]], each with topics = [...]"
            )));
        }
        crate::eval::layer_check::check_layer(
            &p.parameters,
            &format!("{origin}: [parameters]"),
            crate::eval::layer_check::Naming::Keys,
        )?;
        Ok(p)
    }

    /// A built-in preset by name, or a preset file by path (anything ending in `.toml` or naming an
    /// existing file). An unknown name lists the known ones.
    pub fn load(spec: &str) -> Result<Preset> {
        Preset::load_from(spec, Path::new(""))
    }

    /// Like [`Preset::load`], a relative file path taken relative to `base` (a manifest's folder).
    pub fn load_from(spec: &str, base: &Path) -> Result<Preset> {
        if let Some((name, text)) = BUILTIN.iter().find(|(n, _)| *n == spec) {
            return Preset::parse(text, name);
        }
        let path = base.join(spec);
        let path = path.as_path();
        if spec.ends_with(".toml") || path.is_file() || crate::sources::input::is_stream(path) {
            let text = crate::sources::input::read_text_bounded(path, MAX_PRESET_BYTES, "preset")?;
            return Preset::parse(&text, spec);
        }
        Err(Error::InvalidArgument(format!(
            "unknown preset `{spec}`; known: {}, or the path of a preset file (.toml, see presets/ in the repository)",
            known().join(", ")
        )))
    }

    /// True when `topics` hold the reference (if the preset names topics for it) and at least one
    /// estimate.
    pub fn matches(&self, topics: &[TopicInfo]) -> bool {
        let reference = self.reference.topics.is_empty()
            || first_present(&self.reference.topics, topics).is_some();
        reference
            && self
                .estimates
                .iter()
                .any(|e| first_present(&e.topics, topics).is_some())
    }

    /// Picks the inputs in a recording of `topics` at `path`. `reference` and `estimates` given by
    /// the user replace the preset's (an empty `estimates` takes the preset's). Absent estimates
    /// are skipped; an absent reference, or no estimate at all, is a one-line error naming the file,
    /// the preset, the missing topics and what to do.
    pub fn select(
        &self,
        path: &Path,
        topics: &[TopicInfo],
        reference: Option<NamedInput>,
        estimates: Vec<NamedInput>,
    ) -> Result<Selection> {
        let missing = |what: &str, alternatives: &[String], hint: &str| Error::PresetTopicMissing {
            path: path.to_path_buf(),
            preset: self.name.clone(),
            what: what.to_string(),
            topics: alternatives.join(" or "),
            hint: hint.to_string(),
        };
        let reference = match reference {
            Some(r) => r,
            None => {
                let hint = self.reference.note.clone().unwrap_or_else(|| {
                    "give it with --reference TOPIC or --reference-file FILE".into()
                });
                if self.reference.topics.is_empty() {
                    return Err(Error::InvalidArgument(format!(
                        "preset {} names no reference topic: {hint}",
                        self.name
                    )));
                }
                let t = first_present(&self.reference.topics, topics)
                    .ok_or_else(|| missing("reference", &self.reference.topics, &hint))?;
                NamedInput::topic(t)
            }
        };
        if !estimates.is_empty() {
            return Ok(Selection {
                reference,
                estimates,
                skipped: Vec::new(),
            });
        }
        let mut selected = Vec::new();
        let mut skipped = Vec::new();
        for e in &self.estimates {
            match first_present(&e.topics, topics) {
                Some(t) => selected.push(NamedInput::topic(&format!("{}={t}", e.name))),
                None => skipped.push(e.name.clone()),
            }
        }
        if selected.is_empty() {
            let all: Vec<String> = self
                .estimates
                .iter()
                .flat_map(|e| e.topics.iter().cloned())
                .collect();
            return Err(missing(
                "estimate",
                &all,
                "give them with --estimate TOPIC (see `trajdrift topics` for what the recording holds)",
            ));
        }
        Ok(Selection {
            reference,
            estimates: selected,
            skipped,
        })
    }

    /// [`Preset::select`] in the recording (one or more files of a mission, or a folder) at
    /// `recordings`, opened for its topic list (skipped when the user gave both the reference and the
    /// estimates).
    pub fn select_in(
        &self,
        recordings: &[std::path::PathBuf],
        reference: Option<NamedInput>,
        estimates: Vec<NamedInput>,
    ) -> Result<Selection> {
        if let (Some(reference), false) = (&reference, estimates.is_empty()) {
            return Ok(Selection {
                reference: reference.clone(),
                estimates,
                skipped: Vec::new(),
            });
        }
        let path = recordings.first().ok_or_else(|| {
            Error::InvalidArgument(format!(
                "--preset {} picks topics of a RECORDING; pass one",
                self.name
            ))
        })?;
        let topics = crate::sources::open_all(recordings)?.topics()?;
        self.select(path, &topics, reference, estimates)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::config::TrajectoryInput;

    fn topics(names: &[&str]) -> Vec<TopicInfo> {
        names
            .iter()
            .map(|n| TopicInfo {
                topic: n.to_string(),
                type_name: "nav_msgs/msg/Odometry".into(),
                message_encoding: "cdr".into(),
                message_count: 10,
                readable: true,
                frame_pairs: Vec::new(),
                tf_chains: Vec::new(),
            })
            .collect()
    }

    fn topic_of(i: &NamedInput) -> &str {
        match &i.input {
            TrajectoryInput::Topic(t) => t,
            TrajectoryInput::TumFile(_) => panic!("a file"),
        }
    }

    #[test]
    fn every_builtin_parses_and_is_named_like_its_file() {
        for (name, text) in BUILTIN {
            assert_eq!(Preset::parse(text, name).unwrap().name, name);
        }
    }

    #[test]
    fn first_present_alternative_wins() {
        let p = Preset::load("grandtour").unwrap();
        let old = topics(&[
            "/gt_box/inertial_explorer/tc/odometry",
            "/gt_box/dlio/lidar_map_odometry",
        ]);
        let s = p.select(Path::new("a.bag"), &old, None, vec![]).unwrap();
        assert_eq!(
            topic_of(&s.reference),
            "/gt_box/inertial_explorer/tc/odometry"
        );
        assert_eq!(s.estimates[0].name, "dlio");
        assert_eq!(s.skipped, vec!["state_estimator".to_string()]);
        assert_eq!(matching(&old), vec!["grandtour".to_string()]);
        let fomo = topics(&["/warthog/platform/odom"]);
        assert_eq!(matching(&fomo), vec!["fomo".to_string()]);
    }

    #[test]
    fn absent_reference_is_one_line_naming_file_preset_and_topics() {
        let p = Preset::load("grandtour").unwrap();
        let e = p
            .select(
                Path::new("run.bag"),
                &topics(&["/boxi/dlio/lidar_map_odometry"]),
                None,
                vec![],
            )
            .unwrap_err()
            .to_string();
        assert!(!e.contains('\n'), "{e}");
        for part in [
            "run.bag",
            "grandtour",
            "/boxi/inertial_explorer/tc/odometry or /gt_box/inertial_explorer/tc/odometry",
            "--reference",
        ] {
            assert!(e.contains(part), "{part}: {e}");
        }
    }

    #[test]
    fn unknown_name_lists_the_known_ones() {
        let e = Preset::load("kitti").unwrap_err().to_string();
        assert!(e.contains("grandtour, grandtour-prism, fomo"), "{e}");
    }

    #[test]
    fn given_flags_win_over_preset_parameters() {
        let mut p = Preset::load("fomo").unwrap();
        p.parameters.window = Some(vec![10.0]);
        p.parameters.platform = Some(crate::eval::config::Platform::Wheeled);
        let flags = Parameters {
            window: Some(vec![5.0]),
            ..Parameters::default()
        };
        let p = Parameters::layered([&p.parameters, &flags]);
        assert_eq!(p.windows_m(), vec![5.0]);
        assert_eq!(p.platform(), crate::eval::config::Platform::Wheeled);
    }
}

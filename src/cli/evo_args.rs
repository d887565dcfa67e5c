//! The rest of evo's command line: the output and usability flags of `evo_ape`/`evo_rpe` (on
//! `trajdrift ape`/`rpe`), and the whole of `evo_res` (`trajdrift res`) and `evo_traj`
//! (`trajdrift traj`), spelled as evo 1.38.1 spells them (`tests/data/evo-1.38.1-flags.tsv` lists them,
//! read from evo's own parsers). A flag with no meaning here is accepted and named once on stderr
//! ([`ignored_notes`]).
// The flags' doc comments are their `--help` text, written for a terminal (`<mission>`, `[,scale]`),
// not for rustdoc.
#![allow(rustdoc::invalid_html_tags, rustdoc::broken_intra_doc_links)]

use std::path::PathBuf;

use clap::Args;

/// evo's choices of `--plot_mode`.
const PLOT_MODES: [&str; 7] = ["xy", "xz", "yx", "yz", "zx", "zy", "xyz"];

/// The usability flags every evo tool has.
#[derive(Debug, Clone, Default, Args)]
pub struct EvoUsability {
    /// Write every message (results, details) also to FILE.
    #[arg(long = "logfile", value_name = "FILE")]
    pub logfile: Option<PathBuf>,
    /// Replace existing output files without the note (evo: no confirmation questions).
    #[arg(long = "no_warnings")]
    pub no_warnings: bool,
    /// Details on stderr: inputs, association, alignment, files written.
    #[arg(short = 'v', long = "verbose")]
    pub verbose: bool,
    /// Print no results, only warnings and errors.
    #[arg(long = "silent")]
    pub silent: bool,
    /// Like --verbose, and the parsed arguments.
    #[arg(long = "debug")]
    pub debug: bool,
    /// evo's argument JSON ({"flag": value}, evo's names; over the command line).
    #[arg(short = 'c', long = "config", value_name = "FILE")]
    pub config: Option<PathBuf>,
}

/// evo's Rerun viewer flags: accepted, named once on stderr (there is no viewer here; `-p`
/// writes the figures as files).
#[derive(Debug, Clone, Default, Args)]
pub struct EvoViewer {
    /// evo: log to a Rerun viewer (no viewer here; named on stderr).
    #[arg(long = "rerun")]
    pub rerun: bool,
    /// evo: the Rerun recording id (named on stderr).
    #[arg(long = "rerun_rec_id", value_name = "ID")]
    pub rerun_rec_id: Option<String>,
}

impl EvoViewer {
    /// The flags given, for [`ignored_notes`].
    pub fn given(&self) -> [(&'static str, bool, &'static str); 2] {
        [
            (
                "--rerun",
                self.rerun,
                "there is no Rerun viewer; -p writes the figures as files",
            ),
            (
                "--rerun_rec_id",
                self.rerun_rec_id.is_some(),
                "there is no Rerun viewer",
            ),
        ]
    }
}

/// evo's map layers under the trajectory figures: accepted, named once on stderr (not drawn here).
#[derive(Debug, Clone, Default, Args)]
pub struct EvoMapLayers {
    /// evo: a ROS map image under the trajectories (not drawn here; named on stderr).
    #[arg(long = "ros_map_yaml", value_name = "FILE")]
    pub ros_map_yaml: Option<String>,
    /// evo: a map tile layer (not drawn here; named on stderr).
    #[arg(long = "map_tile", value_name = "CRS")]
    pub map_tile: Option<String>,
}

impl EvoMapLayers {
    /// The flags given, for [`ignored_notes`].
    pub fn given(&self) -> [(&'static str, bool, &'static str); 2] {
        [
            (
                "--ros_map_yaml",
                self.ros_map_yaml.is_some(),
                "ROS map images are not drawn",
            ),
            (
                "--map_tile",
                self.map_tile.is_some(),
                "map tiles are not drawn (no network)",
            ),
        ]
    }
}

/// `evo_ape`/`evo_rpe`'s flags beyond the metric: figures, result file, filters, usability.
#[derive(Debug, Clone, Default, Args)]
#[command(allow_negative_numbers = true)]
pub struct EvoMetricArgs {
    /// Write the figures (raw, map, stats): beside --save_results, or to --save_plot FILE.
    #[arg(short = 'p', long = "plot")]
    pub plot: bool,
    /// The axes of the trajectory figure.
    #[arg(long = "plot_mode", value_name = "MODE", default_value = "xyz", value_parser = PLOT_MODES)]
    pub plot_mode: String,
    /// The x axis of the raw figure.
    #[arg(long = "plot_x_dimension", value_name = "DIM", default_value = "seconds",
          value_parser = ["index", "seconds", "distances"])]
    pub plot_x_dimension: String,
    /// Upper bound of the colour map (default: the largest value).
    #[arg(
        long = "plot_colormap_max",
        value_name = "V",
        allow_hyphen_values = true
    )]
    pub plot_colormap_max: Option<f64>,
    /// Lower bound of the colour map (default: the smallest value).
    #[arg(
        long = "plot_colormap_min",
        value_name = "V",
        allow_hyphen_values = true
    )]
    pub plot_colormap_min: Option<f64>,
    /// The colour map's upper bound as this percentile of the values (over --plot_colormap_max).
    #[arg(long = "plot_colormap_max_percentile", value_name = "PERCENT")]
    pub plot_colormap_max_percentile: Option<f64>,
    /// Draw the whole reference, not only its poses associated with the estimate.
    #[arg(long = "plot_full_ref")]
    pub plot_full_ref: bool,
    #[command(flatten)]
    pub map_layers: EvoMapLayers,
    /// Write the figures to FILE_raw.EXT, FILE_map.EXT, FILE_stats.EXT (EXT svg or png).
    #[arg(long = "save_plot", value_name = "FILE")]
    pub save_plot: Option<PathBuf>,
    #[command(flatten)]
    pub viewer: EvoViewer,
    /// Write evo's result file (zip: info.json, stats.json, .npy arrays) that evo_res and
    /// `trajdrift res` read.
    #[arg(long = "save_results", value_name = "FILE.zip")]
    pub save_results: Option<PathBuf>,
    /// Express the values in this unit (m, cm, mm, km; deg, rad).
    #[arg(long = "change_unit", value_name = "UNIT",
          value_parser = ["deg", "rad", "mm", "cm", "m", "km"])]
    pub change_unit: Option<String>,
    /// Keep at most N evenly spaced poses of each trajectory before association.
    #[arg(long = "downsample", value_name = "N")]
    pub downsample: Option<usize>,
    /// Keep a pose only after this much motion since the last kept one (before association).
    #[arg(long = "motion_filter", num_args = 2, value_names = ["DISTANCE", "ANGLE_DEGREES"])]
    pub motion_filter: Option<Vec<f64>>,
    #[command(flatten)]
    pub usability: EvoUsability,
}

/// `trajdrift res`: evo_res's command line, and statistics over runs and comparisons.
#[derive(Debug, Clone, Default, Args)]
pub struct ResArgs {
    /// Result files (.zip of `--save_results`, written by evo or trajdrift).
    #[arg(value_name = "RESULT.zip")]
    pub result_files: Vec<PathBuf>,
    /// Merge the results into one (statistics averaged; arrays averaged or appended).
    #[arg(long = "merge")]
    pub merge: bool,
    /// The raw figure over seconds from the start instead of timestamps.
    #[arg(long = "use_rel_time")]
    pub use_rel_time: bool,
    /// Label each result by its file name instead of its estimate's name.
    #[arg(long = "use_filenames")]
    pub use_filenames: bool,
    /// Do not print or compare the results' titles.
    #[arg(long = "ignore_title")]
    pub ignore_title: bool,
    /// Write the figures (raw, stats, histogram, box_plot, violin_histogram) beside the first result,
    /// or to --save_plot FILE.
    #[arg(short = 'p', long = "plot")]
    pub plot: bool,
    /// Circle markers on the raw values.
    #[arg(long = "plot_markers")]
    pub plot_markers: bool,
    /// Write the figures to FILE_NAME.EXT (EXT svg or png).
    #[arg(long = "save_plot", value_name = "FILE")]
    pub save_plot: Option<PathBuf>,
    /// Write the statistics table: .csv (evo's default), .json or .md.
    #[arg(long = "save_table", value_name = "FILE")]
    pub save_table: Option<PathBuf>,
    #[command(flatten)]
    pub viewer: EvoViewer,
    /// Each statistic's mean ± 95 % interval over repeated runs: results grouped by estimator (the
    /// file name less a trailing run number, `orb_03.zip` → `orb`) and mission (the reference's name).
    #[arg(long = "runs")]
    pub runs: bool,
    /// Paired comparison of estimator B against A (names as for --runs) on the missions both ran.
    #[arg(long = "compare", num_args = 2, value_names = ["A", "B"])]
    pub compare: Option<Vec<String>>,
    /// The statistic --compare compares.
    #[arg(long = "compare_stat", value_name = "STAT", default_value = "rmse")]
    pub compare_stat: String,
    #[command(flatten)]
    pub usability: EvoUsability,
}

/// `trajdrift traj`: evo_traj's command line.
#[derive(Debug, Clone, Default, Args)]
#[command(allow_negative_numbers = true)]
pub struct TrajArgs {
    /// Trajectory files (format detected), or evo's form `tum|kitti|euroc FILE...` or
    /// `bag|bag2|mcap RECORDING TOPIC...`.
    #[arg(value_name = "FORMAT|FILE")]
    pub inputs: Vec<String>,
    /// The reference (a file, or a topic of the recording).
    #[arg(long = "ref", value_name = "REF")]
    pub reference: Option<String>,
    /// Print the information and evo's checks of each trajectory.
    #[arg(short = 'f', long = "full_check")]
    pub full_check: bool,
    /// Umeyama SE(3) alignment onto --ref.
    #[arg(short = 'a', long = "align")]
    pub align: bool,
    /// Correct the scale (Sim(3) with -a, scale only without).
    #[arg(short = 's', long = "correct_scale")]
    pub correct_scale: bool,
    /// Align on the first N associated poses (-1: all).
    #[arg(long = "n_to_align", value_name = "N", allow_hyphen_values = true)]
    pub n_to_align: Option<i64>,
    /// Move each trajectory's first pose onto the reference's.
    #[arg(long = "align_origin")]
    pub align_origin: bool,
    /// Keep only the poses associated with --ref.
    #[arg(long = "sync")]
    pub sync: bool,
    /// Add S seconds to every trajectory's stamps but the reference's.
    #[arg(
        long = "t_offset",
        value_name = "S",
        allow_hyphen_values = true,
        conflicts_with = "time_offset"
    )]
    pub t_offset: Option<f64>,
    /// Offset added to the stamps, seconds, or `auto`: found against --ref by eval's machinery.
    #[arg(
        long = "time-offset",
        value_name = "S|auto",
        allow_hyphen_values = true
    )]
    pub time_offset: Option<String>,
    /// Largest stamp difference of an associated pair, seconds.
    #[arg(long = "t_max_diff", value_name = "S", default_value_t = 0.01)]
    pub t_max_diff: f64,
    /// Association: nearest_time or interpolation.
    #[arg(long = "sync_method", default_value = "nearest_time", value_parser = ["nearest_time", "interpolation"])]
    pub sync_method: String,
    /// Merge the trajectories into one, sorted by stamp.
    #[arg(long = "merge")]
    pub merge: bool,
    /// Project to a plane (z, y or x set to 0) after alignment.
    #[arg(long = "project_to_plane", value_parser = ["xy", "xz", "yz"])]
    pub project_to_plane: Option<String>,
    /// Keep at most N evenly spaced poses of each trajectory.
    #[arg(long = "downsample", value_name = "N")]
    pub downsample: Option<usize>,
    /// Keep a pose only after this much motion since the last kept one.
    #[arg(long = "motion_filter", num_args = 2, value_names = ["DISTANCE", "ANGLE_DEGREES"])]
    pub motion_filter: Option<Vec<f64>>,
    /// A Sim(3) from FILE (JSON x,y,z,qx,qy,qz,qw[,scale], .npy or text 4x4) applied on the left.
    #[arg(long = "transform_left", value_name = "FILE")]
    pub transform_left: Option<String>,
    /// The same applied on the right (in each pose's frame).
    #[arg(long = "transform_right", value_name = "FILE")]
    pub transform_right: Option<String>,
    /// With --transform_right: chain each relative motion times the transform from the first pose.
    #[arg(long = "propagate_transform")]
    pub propagate_transform: bool,
    /// Apply the inverse of the transform.
    #[arg(long = "invert_transform")]
    pub invert_transform: bool,
    /// Write the figures (trajectories, xyz) beside the first input, or to --save_plot FILE.
    #[arg(short = 'p', long = "plot")]
    pub plot: bool,
    /// Time axes from the first stamp.
    #[arg(long = "plot_relative_time")]
    pub plot_relative_time: bool,
    /// The axes of the trajectory figure.
    #[arg(long = "plot_mode", value_name = "MODE", default_value = "xyz", value_parser = PLOT_MODES)]
    pub plot_mode: String,
    #[command(flatten)]
    pub map_layers: EvoMapLayers,
    /// Write the figures to FILE_trajectories.EXT and FILE_xyz.EXT (EXT svg or png).
    #[arg(long = "save_plot", value_name = "FILE")]
    pub save_plot: Option<PathBuf>,
    #[command(flatten)]
    pub viewer: EvoViewer,
    /// Write the information table as CSV.
    #[arg(long = "save_table", value_name = "FILE")]
    pub save_table: Option<PathBuf>,
    /// Write each trajectory as NAME.tum.
    #[arg(long = "save_as_tum")]
    pub save_as_tum: bool,
    /// Write each trajectory as NAME.kitti.
    #[arg(long = "save_as_kitti")]
    pub save_as_kitti: bool,
    /// evo writes a ROS 1 bag: trajdrift writes the MCAP of --save_as_mcap instead.
    #[arg(long = "save_as_bag")]
    pub save_as_bag: bool,
    /// evo writes a rosbag2 folder: trajdrift writes the MCAP of --save_as_mcap instead.
    #[arg(long = "save_as_bag2")]
    pub save_as_bag2: bool,
    /// Write every trajectory as geometry_msgs/msg/PoseStamped on /NAME to one MCAP
    /// (default trajectories.mcap).
    #[arg(long = "save_as_mcap", value_name = "FILE", num_args = 0..=1,
          default_missing_value = "trajectories.mcap")]
    pub save_as_mcap: Option<PathBuf>,
    /// Names as given (paths), not file stems.
    #[arg(long = "show_full_names")]
    pub show_full_names: bool,
    /// evo: every trajectory topic of the bag (named on stderr; list them with `trajdrift topics`).
    #[arg(long = "all_topics", alias = "all_channels")]
    pub all_topics: bool,
    #[command(flatten)]
    pub usability: EvoUsability,
}

/// The notes for flags given that have no meaning in trajdrift: `(flag, why)`.
pub fn ignored_notes(flags: &[(&str, bool, &str)]) -> Vec<String> {
    flags
        .iter()
        .filter(|f| f.1)
        .map(|(flag, _, why)| format!("note: {flag} is accepted but has no effect here: {why}"))
        .collect()
}

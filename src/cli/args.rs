//! Every command-line flag, in one place (clap derive).
// The flags' doc comments are their `--help` text, written for a terminal (`<mission>`, `[,scale]`),
// not for rustdoc.
#![allow(rustdoc::invalid_html_tags, rustdoc::broken_intra_doc_links)]

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use trajdrift::eval::parameters::{positive, word, ParameterFlags};
use trajdrift::params::triple;
use trajdrift::sources::StampSource;

/// Evaluate robot trajectories from positions alone: curvature-based time alignment and Drift Error.
#[derive(Debug, Parser)]
#[command(
    name = "trajdrift",
    version,
    about,
    propagate_version = true,
    after_help = help::TRAJDRIFT
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Find each estimate's clock offset to the reference and its Drift Error.
    #[command(after_help = help::EVAL)]
    Eval(Box<EvalArgs>),
    /// List a recording's channels, their types and counts, and which trajdrift can read.
    #[command(after_help = help::TOPICS)]
    Topics(TopicsArgs),
    /// The clock map of a whole mission: each source's clock, lever arm, rate, gaps, coverage, Drift
    /// Error and APE; every pair's offset, the closure of every triple, the clock domains.
    #[command(after_help = help::AUDIT)]
    Audit(Box<AuditArgs>),
    /// A copy of a mission (one MCAP) with each clock domain's stamps and times moved onto the
    /// reference's clock, every other message unchanged, the audit attached.
    #[command(after_help = help::RESTAMP)]
    Restamp(Box<RestampArgs>),
    /// Write a simulated mission (ROS 2 MCAP) with known truth.
    #[command(after_help = help::SIMULATE)]
    Simulate(SimulateArgs),
    /// Evaluate many missions in parallel (a TOML manifest, or a folder of recordings).
    #[command(after_help = help::BATCH)]
    Batch(Box<BatchArgs>),
    /// Build a batch summary from the per-mission results of several folders (sharded runs).
    #[command(after_help = help::MERGE)]
    Merge(MergeArgs),
    /// Write one topic (or a text trajectory) as TUM or CSV text, e.g. for evo.
    #[command(after_help = help::EXPORT)]
    Export(ExportArgs),
    /// Re-run the evaluation over one parameter's values: DIR/sweep.csv and DIR/sweep.svg.
    #[command(after_help = help::SWEEP)]
    Sweep(Box<SweepArgs>),
    /// Absolute pose error, evo's `evo_ape` command line and numbers (`trajdrift ape tum REF EST -a`).
    #[command(after_help = help::APE)]
    Ape(Box<ApeArgs>),
    /// Relative pose error, evo's `evo_rpe` command line and numbers (`trajdrift rpe tum REF EST -d 1 -u m`).
    #[command(after_help = help::RPE)]
    Rpe(Box<RpeArgs>),
    /// Every clock-offset method side by side (none, spatial, speed, curvature, signed curvature, auto).
    #[command(after_help = help::OFFSET)]
    Offset(Box<OffsetArgs>),
    /// evo_res: the table, figures and files of result zips (evo's or trajdrift's), and statistics
    /// over repeated runs and paired comparisons (`trajdrift res *.zip --use_filenames -p`).
    #[command(after_help = help::RES)]
    Res(Box<crate::cli::evo_args::ResArgs>),
    /// evo_traj: information, checks, conversions, alignment and figures of trajectories
    /// (`trajdrift traj tum a.txt b.txt --ref gt.txt -a -p --save_as_kitti`).
    #[command(after_help = help::TRAJ)]
    Traj(Box<crate::cli::evo_args::TrajArgs>),
    /// How far to trust the time alignment: simulated missions of every kind evaluated with the
    /// defaults and graded against their truth (the calibration table).
    #[command(after_help = help::VALIDATE)]
    Validate(Box<ValidateArgs>),
    /// Write the manual (roff) to stdout, or one page per command into a folder.
    #[command(after_help = help::MAN)]
    Man(ManArgs),
    /// Write the completion script of a shell to stdout.
    #[command(after_help = help::COMPLETIONS)]
    Completions(CompletionsArgs),
}

/// The examples under each command's `--help` (and in its man page): real command lines, the first
/// of `eval`, `topics`, `export`, `sweep` and `offset` on the recording shipped in `fixtures/`. A line
/// ending in `:` starts a section (`trajdrift man` makes it a heading).
pub mod help {
    pub const TRAJDRIFT: &str = "\
Examples:
  trajdrift eval fixtures/sim_ground/mission.mcap --reference /reference/position --estimate /estimate/odom
  trajdrift topics fixtures/sim_ground/mission.mcap
  trajdrift batch missions.toml --out results --jobs 4
  trajdrift eval --help        # every flag of a command, and its examples
  trajdrift man | man -l -     # this manual, with a page per command: trajdrift man --out DIR

Exit status:
  0 ok; 1 failure (one line on stderr naming the file, the topic or the flag, and what to do);
  2 usage error; 3 finished with a warning you must see (a weak time offset, a suspected lever arm
  or clock change, a truncated recording).";

    pub const EVAL: &str = "\
Examples:
  # The simulated recording shipped in fixtures/ (truth: Δt = +0.2 s, scale error 2 %)
  trajdrift eval fixtures/sim_ground/mission.mcap --reference /reference/position --estimate /estimate/odom

  # A GrandTour mission folder with its preset: JSON report, figures and a self-contained HTML page
  trajdrift eval mission/ --preset grandtour --json report.json --plot figures --html report.html

  # Two text trajectories, the estimate named, the clock offset known (no search)
  trajdrift eval --reference-file gt.tum --estimate-file lio=lio.tum --time-offset -0.35";

    pub const AUDIT: &str = "\
Examples:
  # A GrandTour-like mission folder of per-sensor bags: every pose topic is a source
  trajdrift audit clocks/ --json audit.json --html audit.html
  # A mission of per-source MCAP files, the sources named, a TF chain among them
  trajdrift audit mission/ --reference /reference/position --source ins=/ins/odom --source lio=/lio/odom \\
      --source /tf:odom:base_link
  trajdrift audit mission.mcap --preset grandtour-prism -q --json -     # the JSON on stdout

Exit status: 3 when a clock is not constant, a triple does not close or an offset is weak.";

    pub const RESTAMP: &str = "\
Examples:
  # Audit and fix in one go: each file's messages moved by its clock (GrandTour's per-sensor bags)
  trajdrift restamp clocks/ --out fixed.mcap
  # From an audit already made, one computer's topics moved together
  trajdrift restamp mission.mcap --audit audit.json --out fixed.mcap \\
      --domain nuc=/lio/odom,/lio/points,/imu/data
  trajdrift audit fixed.mcap          # every domain now at 0 and constant";

    pub const TOPICS: &str = "\
Examples:
  trajdrift topics fixtures/sim_ground/mission.mcap
  trajdrift topics mission/ --json topics.json      # a folder of per-sensor bags as one mission";

    pub const SIMULATE: &str = "\
Examples:
  trajdrift simulate sim.mcap --truth truth.json --time-offset 0.35 --scale-error 0.01
  trajdrift simulate long.mcap --duration 7200 --est-rate 200 --clock-drift-ppm 50
  trajdrift simulate grandtour/ --grandtour           # per-sensor ROS 1 bags, GrandTour's topics
  # Five sources on four clocks (shared, offset, drifting, stepping), for `trajdrift audit`
  trajdrift simulate clocks/ --grandtour --multi-clock --duration 1200 --seed 3 --truth clocks.json";

    pub const BATCH: &str = "\
Examples:
  trajdrift batch missions.toml --out results --jobs 4 --annotate
  trajdrift batch recordings/ --reference /reference/position --estimate /estimate/odom --out results
  # One task of a Slurm job array (or a Kubernetes Indexed Job); then `trajdrift merge results`
  trajdrift batch missions.toml --out results --shard auto";

    pub const MERGE: &str = "\
Examples:
  trajdrift merge results                       # after every shard of a cluster run has ended
  trajdrift merge run-a run-b --out all";

    pub const EXPORT: &str = "\
Examples:
  trajdrift export fixtures/sim_ground/mission.mcap --topic /estimate/odom est.tum
  trajdrift export mission/ --topic /boxi/dlio/lidar_map_odometry --format csv dlio.csv
  trajdrift export mission.bag --topic /tf:odom:base_link -     # a TF chain, to stdout";

    pub const SWEEP: &str = "\
Examples:
  trajdrift sweep fixtures/sim_ground/mission.mcap --reference /reference/position \\
      --estimate /estimate/odom --param eps-min --values 0.05,0.1,0.2,0.5,1 --out sweep-eps
  trajdrift sweep fixtures/sim_ground/mission.mcap --reference /reference/position \\
      --estimate /estimate/odom --param time-offset --values=-0.3:0.7:0.05 --out sweep-dt";

    pub const APE: &str = "\
Examples:
  trajdrift ape tum groundtruth.tum estimate.tum -a
  trajdrift ape kitti KITTI_00_gt.txt KITTI_00_ORB.txt -as --json ape.json
  trajdrift ape fixtures/sim_ground/mission.mcap --reference /reference/position \\
      --estimate /estimate/odom --time-offset auto -a";

    pub const RPE: &str = "\
Examples:
  trajdrift rpe tum groundtruth.tum estimate.tum -d 1 -u m -a
  trajdrift rpe kitti KITTI_00_gt.txt KITTI_00_ORB.txt -d 100 -u m --all_pairs";

    pub const OFFSET: &str = "\
Examples:
  trajdrift offset fixtures/sim_ground/mission.mcap --reference /reference/position --estimate /estimate/odom
  trajdrift offset tum groundtruth.tum estimate.tum";

    pub const RES: &str = "\
Examples:
  trajdrift res results/*.zip --use_filenames --save_table table.csv -p --save_plot res.svg
  trajdrift res orb_*.zip --runs                    # mean ± 95 % interval over repeated runs
  trajdrift res orb_*.zip vins_*.zip --compare orb vins   # paired comparison on the same missions";

    pub const TRAJ: &str = "\
Examples:
  trajdrift traj tum est.txt --ref gt.txt -a -p --save_plot traj.svg --plot_mode xy
  trajdrift traj tum gt.txt est.txt --full_check      # evo_traj's checks, with counts
  trajdrift traj mcap mission.mcap /odom --save_as_tum   # topics to TUM; --save_as_mcap for MCAP";

    pub const VALIDATE: &str = "\
Examples:
  trajdrift validate                              # 10 missions of every kind: the calibration table
  trajdrift validate --missions 50 --kind legged,step --json grades.json
  trajdrift validate --missions 3 --seed 100      # other seeds, a quick look
  # The accuracy to expect on your recording: 20 missions of its shape, known offsets injected
  trajdrift validate --like fixtures/sim_ground/mission.mcap --reference /reference/position --estimate /estimate/odom --missions 20
  trajdrift validate --reference-file gt.tum --estimate-file lio.tum     # the same, shaped like two TUM files";

    pub const MAN: &str = "\
Examples:
  trajdrift man | man -l -
  trajdrift man --out /usr/local/share/man/man1       # trajdrift.1, trajdrift-eval.1, ...";

    pub const COMPLETIONS: &str = "\
Examples:
  trajdrift completions bash > ~/.local/share/bash-completion/completions/trajdrift
  trajdrift completions zsh > ~/.zfunc/_trajdrift     # a folder on $fpath
  trajdrift completions fish > ~/.config/fish/completions/trajdrift.fish";
}

#[derive(Debug, Args)]
pub struct ManArgs {
    /// Write one page per command (trajdrift.1, trajdrift-eval.1, ...) into DIR instead of the main
    /// page to stdout.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ExportFormatArg {
    Tum,
    Csv,
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The recording (MCAP, ROS 1 bag, rosbag2 folder), several files of one mission or a mission
    /// folder, or a text trajectory file; then OUT, the output file (`-` = stdout).
    #[arg(required = true, num_args = 1.., value_name = "RECORDING... OUT")]
    pub recording: Vec<PathBuf>,
    /// The topic to write (not needed for a text file).
    #[arg(long, value_name = "TOPIC")]
    pub topic: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "tum")]
    pub format: ExportFormatArg,
    /// Output file (`-` = stdout): the last positional argument, taken from `recording` by the
    /// command (clap cannot end a list of positionals with another one).
    #[arg(skip)]
    pub out: PathBuf,
    /// Which stamp to use: header or log.
    #[arg(long, value_name = "WORD", default_value = "header", value_parser = word::<StampSource>())]
    pub stamp: StampSource,
    #[command(flatten)]
    pub text: TextArgs,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct EvalArgs {
    /// The recording (MCAP, ROS 1 bag, rosbag2 folder), or several files of one mission (e.g. a
    /// GrandTour mission's bags), or a mission folder. Optional when both sides are text files.
    pub recording: Vec<PathBuf>,
    /// Reference topic.
    #[arg(long, value_name = "TOPIC", required_unless_present_any = ["reference_file", "preset"])]
    pub reference: Option<String>,
    /// Reference from a text file (TUM, KITTI, EuRoC, CSV) instead of a topic.
    #[arg(long, value_name = "FILE", conflicts_with = "reference")]
    pub reference_file: Option<PathBuf>,
    /// Estimate topic, optionally named (repeatable).
    #[arg(long, value_name = "[NAME=]TOPIC")]
    pub estimate: Vec<String>,
    /// Estimate from a text file (TUM, KITTI, EuRoC, CSV), optionally named (repeatable).
    #[arg(long, value_name = "[NAME=]FILE")]
    pub estimate_file: Vec<String>,
    #[command(flatten)]
    pub params: ParameterFlags,
    /// Write the JSON report to FILE (`-` = stdout).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Print nothing but errors and warnings.
    #[arg(long, short)]
    pub quiet: bool,
    /// Write the estimate shifted onto the reference clock (as evaluated) as TUM, for evo. With several
    /// estimates the name goes before the extension: FILE.tum → FILE.NAME.tum.
    #[arg(long, value_name = "FILE")]
    pub export_aligned: Option<PathBuf>,
    /// Also write the recording with the results added (aligned estimate, Drift Error windows,
    /// curvature, metadata and report) to OUT.mcap.
    #[arg(long, value_name = "OUT.mcap")]
    pub annotate: Option<PathBuf>,
    /// Replace an existing --annotate output.
    #[arg(long)]
    pub force: bool,
    /// Reference sensor position relative to the common body point, body frame, metres; or
    /// tf-static:[BODY:]FRAME: FRAME's offset in BODY from /tf_static (BODY defaults to CHILD of the
    /// /tf:PARENT:CHILD inputs).
    #[arg(
        long,
        value_name = "X,Y,Z|tf-static:[BODY:]FRAME",
        allow_hyphen_values = true
    )]
    pub reference_lever: Option<String>,
    /// Estimate sensor position relative to the common body point, body frame, metres; the estimate
    /// is moved onto the reference's point (p − R·(l_est − l_ref)) before alignment (repeatable, NAME= for one estimate).
    /// tf-static:[BODY:]FRAME takes FRAME's offset in BODY from /tf_static (BODY defaults to CHILD of
    /// the /tf:PARENT:CHILD inputs).
    #[arg(
        long,
        value_name = "[NAME=]X,Y,Z|tf-static:[BODY:]FRAME",
        allow_hyphen_values = true
    )]
    pub estimate_lever: Vec<String>,
    /// The usual topics of a dataset: a built-in preset (grandtour, grandtour-prism, fomo) or a preset
    /// file (.toml, see presets/). --reference/--estimate given replace the preset's.
    #[arg(long, value_name = "NAME|FILE")]
    pub preset: Option<String>,
    #[command(flatten)]
    pub text: TextArgs,
    /// Write the figures (top view, Drift Error, offset search and profile, speed) into DIR.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Format of the --plot figures.
    #[arg(long, value_enum, default_value = "svg")]
    pub plot_format: PlotFormatArg,
    /// Write a self-contained HTML report (figures inline, nothing loaded from the network) to FILE.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum TextFormatArg {
    Tum,
    Kitti,
    Euroc,
    Csv,
}

/// How text trajectory files are read.
#[derive(Debug, Args)]
pub struct TextArgs {
    /// Format of the text files (default: picked per file from extension and content).
    #[arg(long, value_enum)]
    pub text_format: Option<TextFormatArg>,
    /// Column mapping of CSV files, e.g. t=t:us,x=px,y=py,z=pz,qx=qx,qy=qy,qz=qz,qw=qw (time unit s|ms|us|ns).
    #[arg(long, value_name = "MAPPING")]
    pub csv: Option<String>,
    /// KITTI times.txt for KITTI pose files (default: frame i at i·0.1 s).
    #[arg(long, value_name = "FILE")]
    pub kitti_times: Option<PathBuf>,
}

/// Which sources an audit takes (shared by `audit` and `restamp`).
#[derive(Debug, Args)]
pub struct SourceArgs {
    /// The reference topic (default: the preset's, or the position-only topic with the most
    /// messages).
    #[arg(long, value_name = "TOPIC")]
    pub reference: Option<String>,
    /// A source, optionally named (repeatable; TF chains /tf:PARENT:CHILD work). Default: every
    /// readable pose or position topic, and the preset's estimates.
    #[arg(long, value_name = "[NAME=]TOPIC")]
    pub source: Vec<String>,
    /// The usual topics of a dataset: a built-in preset (grandtour, grandtour-prism, fomo) or a preset
    /// file; its reference is the audit's.
    #[arg(long, value_name = "NAME|FILE")]
    pub preset: Option<String>,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct AuditArgs {
    /// The recording (MCAP, ROS 1 bag, rosbag2 folder), several files of one mission, or a mission
    /// folder (each file read once, all sources in one pass).
    #[arg(required = true, num_args = 1..)]
    pub recording: Vec<PathBuf>,
    #[command(flatten)]
    pub sources: SourceArgs,
    /// Write the audit as JSON to FILE (`-` = stdout; schemas/audit.schema.json).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write a self-contained HTML page (offset matrix, clocks by domain, closure, profiles) to FILE.
    #[arg(long, value_name = "FILE")]
    pub html: Option<PathBuf>,
    /// Print nothing but errors and warnings.
    #[arg(long, short)]
    pub quiet: bool,
    #[command(flatten)]
    pub params: ParameterFlags,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct RestampArgs {
    /// The recording (MCAP, ROS 1 bag, rosbag2 folder), several files of one mission, or a mission
    /// folder; never modified.
    #[arg(required = true, num_args = 1..)]
    pub recording: Vec<PathBuf>,
    /// The output: one MCAP holding every message of the input.
    #[arg(long, value_name = "FIXED.mcap")]
    pub out: PathBuf,
    /// An audit of the same recording (`trajdrift audit --json`); without it the audit is run first.
    #[arg(long, value_name = "AUDIT.json")]
    pub audit: Option<PathBuf>,
    /// A clock domain: topics recorded on one clock, moved together by the clock of the audited
    /// sources among them (repeatable). Default: each source's file (a mission of several files), or
    /// its topic alone.
    #[arg(long, value_name = "NAME=TOPIC,...")]
    pub domain: Vec<String>,
    /// Replace an existing output.
    #[arg(long)]
    pub force: bool,
    /// Print nothing but errors and warnings.
    #[arg(long, short)]
    pub quiet: bool,
    #[command(flatten)]
    pub sources: SourceArgs,
    #[command(flatten)]
    pub params: ParameterFlags,
}

#[derive(Debug, Args)]
pub struct TopicsArgs {
    /// The recording (MCAP, ROS 1 bag, rosbag2 folder), several files of one mission, or a mission
    /// folder.
    #[arg(required = true, num_args = 1..)]
    pub recording: Vec<PathBuf>,
    /// Write the list as JSON to FILE (`-` = stdout).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct SimulateArgs {
    /// Output recording (.mcap).
    pub out: PathBuf,
    /// Also write the truth as JSON here.
    #[arg(long, value_name = "FILE")]
    pub truth: Option<PathBuf>,
    /// Random seed.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Clock offset Δt of the estimate, seconds, in [-86400, 86400].
    #[arg(long, default_value_t = 0.2, allow_hyphen_values = true)]
    pub time_offset: f64,
    /// Scale error of the estimate (0.02 = 2 % too long), in [-0.5, 0.5].
    #[arg(long, default_value_t = 0.02, allow_hyphen_values = true)]
    pub scale_error: f64,
    /// Estimate sensor position in the body frame, x,y,z metres, each in [-1000, 1000].
    #[arg(
        long,
        value_name = "X,Y,Z",
        default_value = "0,0.3,0",
        allow_hyphen_values = true,
        value_parser = triple
    )]
    pub lever: [f64; 3],
    /// Repeat the route this many times (longer missions), up to 6 hours of mission.
    #[arg(long, default_value_t = 1, conflicts_with = "duration")]
    pub laps: usize,
    /// Repeat the route to last exactly this long, seconds (instead of --laps), in [1, 21600].
    #[arg(long, value_name = "S", value_parser = positive)]
    pub duration: Option<f64>,
    /// Rate of the estimate (Odometry), Hz, in (0, 1000], at most 1e7 samples in the mission.
    #[arg(long, value_name = "HZ", default_value_t = 20.0, value_parser = positive)]
    pub est_rate: f64,
    /// Add an unrelated bulk channel (like lidar) totalling about this many MiB.
    #[arg(long, value_name = "MIB", default_value_t = 0)]
    pub bulk_mib: u64,
    /// Replace existing outputs (OUT and --truth).
    #[arg(long)]
    pub force: bool,
    /// Clock rate error of the estimate, ppm (positive: its clock runs fast), in [-10000, 10000].
    #[arg(
        long,
        value_name = "PPM",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub clock_drift_ppm: f64,
    /// A step of the estimate's clock: from AT seconds on, its Δt is OFFSET (a recorder restart, an
    /// NTP correction). Samples whose stamp would not increase are dropped.
    #[arg(long, value_name = "AT:OFFSET", allow_hyphen_values = true)]
    pub clock_step: Option<trajdrift::simulate::ClockStep>,
    /// Write a GrandTour-like mission instead: OUT is a folder of per-sensor ROS 1 bags
    /// (`<stamp>_cpt7_ie_tc.bag`, `_ap20_prism_position.bag`, `_dlio.bag`, `_anymal_state.bag`,
    /// `_tf_minimal.bag`) with GrandTour's topic names and frames.
    #[arg(long)]
    pub grandtour: bool,
    /// With --grandtour: the same messages in one `<stamp>_merged.bag`.
    #[arg(long, requires = "grandtour")]
    pub merged: bool,
    /// With --grandtour: a mission of several sources on several clocks, drawn from --seed: the prism
    /// as reference, the INS on its clock, DLIO offset, the state estimator drifting, open3d_slam
    /// stepping (`_open3d_slam.bag`), each with its own lever arm; --truth gets each source's clock
    /// and lever. --duration sets the length (the step falls in its middle third).
    #[arg(long, requires = "grandtour")]
    pub multi_clock: bool,
}

#[derive(Debug, Args)]
pub struct BatchArgs {
    /// A manifest (.toml), or a folder of recordings (.mcap, also one level down).
    pub input: PathBuf,
    /// For a folder: the reference topic.
    #[arg(long, value_name = "TOPIC")]
    pub reference: Option<String>,
    /// For a folder: estimate topic, optionally named (repeatable).
    #[arg(long, value_name = "[NAME=]TOPIC")]
    pub estimate: Vec<String>,
    /// For a folder: the topics of a dataset (a built-in preset or a preset file), like `eval --preset`.
    #[arg(long, value_name = "NAME|FILE")]
    pub preset: Option<String>,
    /// Evaluation parameters for every mission, over the manifest's and the preset's.
    #[command(flatten)]
    pub params: ParameterFlags,
    /// Output folder: <mission>.json, <mission>.mcap, summary.{json,csv,md}.
    #[arg(long, value_name = "DIR", default_value = "trajdrift-batch")]
    pub out: PathBuf,
    /// Missions at once (default: the number of cores).
    #[arg(long, short, value_name = "N")]
    pub jobs: Option<usize>,
    /// Also write each mission's annotated recording, <mission>.mcap.
    #[arg(long)]
    pub annotate: bool,
    /// Replace existing annotated recordings.
    #[arg(long)]
    pub force: bool,
    /// Keep missions already done in --out (resume an interrupted run).
    #[arg(long)]
    pub skip_existing: bool,
    /// Run only shard I of N (1-based), or `auto`: the shard from a Slurm job array
    /// (SLURM_ARRAY_TASK_ID/_MIN/_COUNT) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX). Each shard
    /// writes its own summary-shard-I-of-N.*; `trajdrift merge` builds the summary of all shards.
    #[arg(long, value_name = "I/N|auto")]
    pub shard: Option<String>,
    /// The shard count for `--shard auto` when the scheduler gives only an index (Kubernetes);
    /// default: the TRAJDRIFT_SHARDS variable.
    #[arg(long, value_name = "N")]
    pub shards: Option<usize>,
    /// Also write each mission's figures into DIR/<mission>_figures/.
    #[arg(long)]
    pub plot: bool,
    /// Format of the --plot figures.
    #[arg(long, value_enum, default_value = "svg")]
    pub plot_format: PlotFormatArg,
    /// Also write each mission's self-contained HTML report, DIR/<mission>.html (summary.html links it).
    #[arg(long)]
    pub html: bool,
    /// Audit every mission instead (`trajdrift audit`): DIR/<mission>.audit.json, and a summary listing
    /// each mission's clock domains and the sources out of line. A folder's subfolder of recordings is
    /// one mission; --reference/--preset pick the reference, every pose topic is a source.
    #[arg(long)]
    pub audit: bool,
    /// Print nothing but errors and warnings.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Folders holding per-mission results (<mission>.json).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Where to write summary.{json,csv,md,html} (default: the first folder).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Merge an incomplete or inconsistent set anyway (missing shards, mismatched parameters,
    /// unreadable results): the summary is marked partial and lists what is wrong (exit 3 at best).
    #[arg(long)]
    pub allow_partial: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Turns the text flags into the library's reading options.
pub fn text_options(a: &TextArgs) -> trajdrift::Result<trajdrift::sources::text::TextOptions> {
    use trajdrift::sources::text::TextFormat;
    Ok(trajdrift::sources::text::TextOptions {
        format: a.text_format.map(|f| match f {
            TextFormatArg::Tum => TextFormat::Tum,
            TextFormatArg::Kitti => TextFormat::Kitti,
            TextFormatArg::Euroc => TextFormat::Euroc,
            TextFormatArg::Csv => TextFormat::Csv,
        }),
        csv: a
            .csv
            .as_deref()
            .map(trajdrift::sources::mapped_csv::CsvMapping::parse)
            .transpose()?,
        kitti_times: a.kitti_times.clone(),
    })
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum PlotFormatArg {
    Svg,
    /// bitmap, drawn with the font built into the binary
    Png,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum SweepParamArg {
    /// --eps-min (both ε, the paper's ε_min)
    EpsMin,
    CurvatureEps,
    PathEps,
    /// --window (one size per value)
    Window,
    LeverArm,
    Overlap,
    /// --time-offset: the applied Δt (no search); each method's Δt is marked
    TimeOffset,
}

/// `trajdrift sweep`: every `eval` flag, plus the parameter, its values and the output folder.
#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct SweepArgs {
    /// The parameter to vary.
    #[arg(long, value_enum)]
    pub param: SweepParamArg,
    /// Its values: a list (0.05,0.1,0.2) or a range A:B:STEP (0.05:1:0.05).
    #[arg(long, value_name = "LIST|A:B:STEP", allow_hyphen_values = true)]
    pub values: String,
    /// Output folder for sweep.csv and sweep.svg.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub eval: EvalArgs,
}

/// The inputs and pipeline flags shared by `ape` and `rpe` (evo's spelling, plus trajdrift's own).
#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct MetricArgs {
    /// evo's form `tum|kitti|euroc REF EST` or `bag|bag2|mcap RECORDING REF_TOPIC EST_TOPIC`, or a
    /// RECORDING with --reference/--estimate (TF chains /tf:PARENT:CHILD work), or nothing with
    /// --reference-file/--estimate-file.
    #[arg(value_name = "FORMAT|RECORDING", num_args = 0..=4)]
    pub inputs: Vec<String>,
    /// Reference topic (native form).
    #[arg(long, value_name = "TOPIC")]
    pub reference: Option<String>,
    /// Reference text file (native form; TUM, KITTI, EuRoC, CSV).
    #[arg(long, value_name = "FILE", conflicts_with = "reference")]
    pub reference_file: Option<PathBuf>,
    /// Estimate topic (native form).
    #[arg(long, value_name = "TOPIC")]
    pub estimate: Option<String>,
    /// Estimate text file (native form).
    #[arg(long, value_name = "FILE", conflicts_with = "estimate")]
    pub estimate_file: Option<PathBuf>,
    /// A preset's reference and first estimate (native form).
    #[arg(long, value_name = "NAME|FILE")]
    pub preset: Option<String>,
    /// Which stamp to use (native form): header or log.
    #[arg(long, value_name = "WORD", default_value = "header", value_parser = word::<StampSource>())]
    pub stamp: StampSource,
    #[command(flatten)]
    pub text: TextArgs,
    /// Pose relation.
    #[arg(short = 'r', long = "pose_relation", alias = "pose-relation", default_value = "trans_part",
          value_parser = ["trans_part", "rot_part", "full", "angle_deg", "angle_rad", "point_distance", "point_distance_error_ratio"])]
    pub pose_relation: String,
    /// Umeyama SE(3) alignment on positions (evo -a).
    #[arg(short = 'a', long = "align")]
    pub align: bool,
    /// Correct scale: Sim(3) with -a, scale only without (evo -s).
    #[arg(short = 's', long = "correct_scale", alias = "correct-scale")]
    pub correct_scale: bool,
    /// Align on the first N pairs only.
    #[arg(
        long = "n_to_align",
        alias = "n-to-align",
        value_name = "N",
        allow_hyphen_values = true
    )]
    pub n_to_align: Option<i64>,
    /// Move the estimate's first pose onto the reference's.
    #[arg(long = "align_origin", alias = "align-origin", conflicts_with_all = ["align", "align_yaw"])]
    pub align_origin: bool,
    /// 4-DoF alignment (yaw + translation) for gravity-aligned frames (not in evo).
    #[arg(long = "align-yaw", conflicts_with_all = ["align", "correct_scale"])]
    pub align_yaw: bool,
    /// Largest stamp difference of an associated pair, seconds.
    #[arg(
        long = "t_max_diff",
        alias = "t-max-diff",
        value_name = "S",
        default_value_t = 0.01
    )]
    pub t_max_diff: f64,
    /// Known offset added to the estimate's stamps for association, seconds (evo --t_offset).
    #[arg(
        long = "t_offset",
        value_name = "S",
        allow_hyphen_values = true,
        conflicts_with = "time_offset"
    )]
    pub t_offset: Option<f64>,
    /// Offset added to the estimate's stamps, seconds, or `auto`: found by eval's machinery.
    #[arg(
        long = "time-offset",
        value_name = "S|auto",
        allow_hyphen_values = true
    )]
    pub time_offset: Option<String>,
    /// Crop the reference from this stamp, seconds (its own clock).
    #[arg(long = "t_start", value_name = "S", allow_hyphen_values = true)]
    pub t_start: Option<f64>,
    /// Crop the reference up to this stamp, seconds.
    #[arg(long = "t_end", value_name = "S", allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Association: snap to the nearest pose, or interpolate the longer trajectory.
    #[arg(long = "sync_method", alias = "sync-method", default_value = "nearest_time",
          value_parser = ["nearest_time", "interpolation"])]
    pub sync_method: String,
    /// Project both trajectories to a plane after alignment.
    #[arg(long = "project_to_plane", alias = "project-to-plane", value_parser = ["xy", "xz", "yz"])]
    pub project_to_plane: Option<String>,
    /// Write the result as JSON to FILE (`-` = stdout).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct ApeArgs {
    #[command(flatten)]
    pub common: MetricArgs,
    #[command(flatten)]
    pub evo: crate::cli::evo_args::EvoMetricArgs,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct RpeArgs {
    #[command(flatten)]
    pub common: MetricArgs,
    #[command(flatten)]
    pub evo: crate::cli::evo_args::EvoMetricArgs,
    /// Delta between the poses of a pair.
    #[arg(short = 'd', long = "delta", default_value_t = 1.0)]
    pub delta: f64,
    /// Unit of delta: f (frames), m (metres of path), d (degrees), r (radians).
    #[arg(short = 'u', long = "delta_unit", alias = "delta-unit", default_value = "f", value_parser = ["f", "m", "d", "r"])]
    pub delta_unit: String,
    /// Relative tolerance of the delta in --all_pairs mode.
    #[arg(
        short = 't',
        long = "delta_tol",
        alias = "delta-tol",
        default_value_t = 0.1
    )]
    pub delta_tol: f64,
    /// Every pair at the delta, not consecutive ones.
    #[arg(long = "all_pairs", alias = "all-pairs")]
    pub all_pairs: bool,
    /// Choose the pairs on the reference instead of the estimate.
    #[arg(long = "pairs_from_reference", alias = "pairs-from-reference")]
    pub pairs_from_reference: bool,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct OffsetArgs {
    #[command(flatten)]
    pub common: MetricArgs,
    /// The spatial method searches Δt in ±S seconds.
    #[arg(long, value_name = "S", default_value_t = 5.0)]
    pub spatial_range: f64,
}

#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("like_reference").args(["reference", "reference_file"])))]
#[command(group(clap::ArgGroup::new("like_estimate").args(["estimate", "estimate_file"])))]
pub struct ValidateArgs {
    /// Missions of each kind (1–10000).
    #[arg(long, value_name = "N", default_value_t = 10,
          value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub missions: u32,
    /// Only these kinds (comma-separated): ground, legged, near_straight, turns_in_place,
    /// gnss_outages, receipt_stamps, position_jumps, drift, short_drift, step.
    #[arg(long, value_name = "KIND,...", value_delimiter = ',')]
    pub kind: Vec<trajdrift::simulate::scenario::MissionKind>,
    /// The first seed (mission i of a kind has seed S + i).
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Write every mission's grade as JSON to FILE (`-` = stdout).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Missions shaped like this recording instead (MCAP, ROS 1 bag, rosbag2 folder, several files of
    /// one mission or a mission folder): its reference's route, both rates and noise levels, its
    /// outages; known clock offsets injected. Needs a reference and an estimate (topics or files).
    #[arg(long, value_name = "RECORDING", num_args = 1.., conflicts_with = "kind",
          requires_all = ["like_reference", "like_estimate"])]
    pub like: Vec<PathBuf>,
    /// With --like: the reference topic.
    #[arg(long, value_name = "TOPIC", requires = "like")]
    pub reference: Option<String>,
    /// With --like: the estimate topic.
    #[arg(long, value_name = "TOPIC", requires = "like")]
    pub estimate: Option<String>,
    /// Missions shaped like this text trajectory's (TUM, KITTI, EuRoC, CSV) as the reference, with
    /// --estimate-file (or --like's estimate topic).
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with = "kind",
        requires = "like_estimate"
    )]
    pub reference_file: Option<PathBuf>,
    /// The estimate from a text file, for missions shaped like it and the reference.
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with = "kind",
        requires = "like_reference"
    )]
    pub estimate_file: Option<PathBuf>,
}

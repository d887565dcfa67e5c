//! Every command-line flag, in one place (clap derive).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// Evaluate robot trajectories from positions alone: curvature-based time alignment and Drift Error.
#[derive(Debug, Parser)]
#[command(name = "trajdrift", version, about, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Find each estimate's clock offset to the reference and its Drift Error.
    Eval(Box<EvalArgs>),
    /// List a recording's channels, their types and counts, and which trajdrift can read.
    Topics(TopicsArgs),
    /// Write a simulated mission (ROS 2 MCAP) with known truth.
    Simulate(SimulateArgs),
    /// Evaluate many missions in parallel (a TOML manifest, or a folder of recordings).
    Batch(BatchArgs),
    /// Build a batch summary from the per-mission results of several folders (sharded runs).
    Merge(MergeArgs),
    /// Write one topic (or a text trajectory) as TUM or CSV text, e.g. for evo.
    Export(ExportArgs),
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ExportFormatArg {
    Tum,
    Csv,
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The recording (MCAP, ROS 1 bag, rosbag2 folder), or a text trajectory file.
    pub recording: PathBuf,
    /// The topic to write (not needed for a text file).
    #[arg(long, value_name = "TOPIC")]
    pub topic: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "tum")]
    pub format: ExportFormatArg,
    /// Output file (`-` = stdout).
    pub out: PathBuf,
    /// Which stamp to use.
    #[arg(long, value_enum, default_value = "header")]
    pub stamp: StampArg,
    #[command(flatten)]
    pub text: TextArgs,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum PlatformArg {
    /// the paper's ε 0.1 m, Δt_max as --dt-max
    Legged,
    /// the paper's ε 0.3 m, Δt_max as --dt-max
    Wheeled,
    /// ε and the curvature Δt_max from the reference's measured noise and speed
    Auto,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum StampArg {
    /// header.stamp (when the sensor measured)
    Header,
    /// MCAP log time (when the recorder received it)
    Log,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum OffsetMethodArg {
    /// unsigned curvature, eq. (2) (the paper)
    Curvature,
    /// windowed speed profile (blind at constant speed)
    Speed,
    /// signed horizontal curvature, mean-removed NCC
    SignedCurvature,
    /// run them all, apply a confident and consistent answer
    Auto,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum LeverCorrectionArg {
    /// α = r_ref/r_est where |r_est − r_ref| ≤ a (the paper)
    Paper,
    None,
    /// fit s and the lateral lever d of L_est = s·(L_ref − d·Δψ) over all windows, correct by d
    Fit,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct EvalArgs {
    /// The recording (MCAP, ROS 1 bag or rosbag2 folder). Optional when both sides are text files.
    pub recording: Option<PathBuf>,
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
    /// Which stamp to use.
    #[arg(long, value_enum, default_value = "header")]
    pub stamp: StampArg,
    /// ENU origin for NavSatFix topics: lat,lon,h (default: the first valid fix).
    #[arg(long, value_name = "LAT,LON,H", allow_hyphen_values = true)]
    pub origin: Option<String>,
    /// Platform: the paper's ε_min (legged 0.1 m, wheeled 0.3 m), or auto: measured on the reference.
    #[arg(long, value_enum, default_value = "auto")]
    pub platform: PlatformArg,
    /// ε_min for both curvature and path length (the paper's single ε), metres.
    #[arg(long, value_name = "M")]
    pub eps_min: Option<f64>,
    /// ε for curvature, metres (overrides --eps-min).
    #[arg(long, value_name = "M")]
    pub curvature_eps: Option<f64>,
    /// ε for path-length decimation, metres (overrides --eps-min).
    #[arg(long, value_name = "M")]
    pub path_eps: Option<f64>,
    /// θ_max: turning angles above it are discontinuities, radians.
    #[arg(long, value_name = "RAD", default_value_t = std::f64::consts::FRAC_PI_2)]
    pub theta_max: f64,
    /// Δt_max: a chord slower than this marks a stationary robot or a gap, seconds [default: 2 for
    /// gaps and standstills; the curvature's from the robot's speed with --platform auto].
    #[arg(long, value_name = "S")]
    pub dt_max: Option<f64>,
    /// Drift Error window sizes, metres of reference path (comma-separated).
    #[arg(
        long,
        value_name = "M[,M...]",
        value_delimiter = ',',
        default_value = "5"
    )]
    pub window: Vec<f64>,
    /// Window overlap as a fraction in [0, 1).
    #[arg(long, default_value_t = 0.0)]
    pub overlap: f64,
    /// Lever-arm correction of path lengths.
    #[arg(long, value_enum, default_value = "fit")]
    pub lever_correction: LeverCorrectionArg,
    /// Expected lever arm a between the two sensors, metres (bound of the paper's correction).
    #[arg(long, value_name = "M", default_value_t = 0.1)]
    pub lever_arm: f64,
    /// Time-offset method applied.
    #[arg(long, value_enum, default_value = "auto")]
    pub offset_method: OffsetMethodArg,
    /// Largest offset searched, seconds (GPS time and UTC alone differ by 18 s).
    #[arg(long, value_name = "S", default_value_t = 30.0)]
    pub max_offset: f64,
    /// Fine grid step of the offset search, seconds.
    #[arg(long, value_name = "S", default_value_t = 0.001)]
    pub grid: f64,
    /// Skip the search and apply this offset, seconds (t_est + offset = reference clock).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub time_offset: Option<f64>,
    /// Crop start on the reference clock: epoch seconds, or seconds from the first reference sample.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub t_start: Option<f64>,
    /// Crop end, like --t-start.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub t_end: Option<f64>,
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
    /// Flags set on the command line (clap ids), filled by [`crate::cli::parse`]: they win over a
    /// preset's parameters.
    #[arg(skip)]
    pub given: Vec<String>,
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

#[derive(Debug, Args)]
pub struct TopicsArgs {
    /// The recording (MCAP, ROS 1 bag or rosbag2 folder).
    pub recording: PathBuf,
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
    /// Clock offset Δt of the estimate, seconds.
    #[arg(long, default_value_t = 0.2, allow_hyphen_values = true)]
    pub time_offset: f64,
    /// Scale error of the estimate (0.02 = 2 % too long).
    #[arg(long, default_value_t = 0.02, allow_hyphen_values = true)]
    pub scale_error: f64,
    /// Estimate sensor position in the body frame, x,y,z metres.
    #[arg(
        long,
        value_name = "X,Y,Z",
        default_value = "0,0.3,0",
        allow_hyphen_values = true
    )]
    pub lever: String,
    /// Repeat the route this many times (longer missions).
    #[arg(long, default_value_t = 1)]
    pub laps: usize,
    /// Add an unrelated bulk channel (like lidar) totalling about this many MiB.
    #[arg(long, value_name = "MIB", default_value_t = 0)]
    pub bulk_mib: u64,
    /// Replace an existing output.
    #[arg(long)]
    pub force: bool,
    /// Clock rate error of the estimate, ppm (positive: its clock runs fast).
    #[arg(
        long,
        value_name = "PPM",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub clock_drift_ppm: f64,
}

/// Parses `a,b,c` into three numbers.
pub fn parse_triple(flag: &str, s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{flag} takes three comma-separated numbers, got `{s}`"))?;
    <[f64; 3]>::try_from(v)
        .map_err(|_| format!("{flag} takes three comma-separated numbers, got `{s}`"))
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
    /// Run only shard I of N (1-based); `trajdrift merge` builds the summary of all shards.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Print nothing but errors and warnings.
    #[arg(long, short)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Folders holding per-mission results (<mission>.json).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Where to write summary.{json,csv,md} (default: the first folder).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
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

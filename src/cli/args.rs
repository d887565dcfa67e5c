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
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
pub struct EvalArgs {
    /// The recording (.mcap). Optional when both sides are text files.
    pub recording: Option<PathBuf>,
    /// Reference topic.
    #[arg(long, value_name = "TOPIC", required_unless_present = "reference_file")]
    pub reference: Option<String>,
    /// Reference from a TUM file instead of a topic.
    #[arg(long, value_name = "FILE", conflicts_with = "reference")]
    pub reference_file: Option<PathBuf>,
    /// Estimate topic, optionally named (repeatable).
    #[arg(long, value_name = "[NAME=]TOPIC")]
    pub estimate: Vec<String>,
    /// Estimate from a TUM file, optionally named (repeatable).
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
    #[arg(long, value_enum, default_value = "paper")]
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
}

#[derive(Debug, Args)]
pub struct TopicsArgs {
    /// The recording (.mcap).
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

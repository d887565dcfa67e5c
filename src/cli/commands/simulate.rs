//! `trajdrift simulate`: write a simulated mission with known truth (the project's own fixtures and the
//! memory benchmark's large recordings come from here).

use anyhow::{anyhow, Result};

use trajdrift::output::{write_json, OutputFile, OutputGuard};
use trajdrift::simulate::grandtour::{grandtour_files, write_grandtour, GrandTourOptions};
use trajdrift::simulate::writer::{truth_json, write_mcap};
use trajdrift::simulate::{default_route, route_of_duration, simulate, MissionConfig};

use crate::cli::args::SimulateArgs;
use crate::cli::EXIT_OK;

/// `--grandtour`'s options: the bulk split over the sensor bags.
fn grandtour_options(a: &SimulateArgs) -> GrandTourOptions {
    GrandTourOptions {
        merged: a.merged,
        ..GrandTourOptions::default()
    }
}

/// Every output claimed before anything is simulated: OUT (a file, or with `--grandtour` a folder and
/// its bags) and `--truth`, never one path twice.
fn claim_outputs(a: &SimulateArgs) -> Result<()> {
    let mut guard = OutputGuard::default();
    if a.grandtour {
        guard.claim_dir("OUT", &a.out)?;
        let files = if a.multi_clock {
            trajdrift::simulate::grandtour::multi_clock_files(&a.out, a.merged)
        } else {
            grandtour_files(&a.out, &grandtour_options(a))
        };
        for f in files {
            guard.claim("OUT", &f)?;
        }
    } else {
        guard.claim("OUT", &a.out)?;
    }
    if let Some(path) = &a.truth {
        guard.claim("--truth", path)?;
    }
    Ok(())
}

/// `--grandtour`: the mission as a folder of per-sensor bags (the bulk split over the sensor bags).
fn grandtour(
    a: &SimulateArgs,
    mission: &trajdrift::simulate::Mission,
    bulk_bytes: usize,
) -> Result<u8> {
    let mut options = grandtour_options(a);
    let sensor_bags = options.bags.len() - 1;
    options.bulk_bytes = bulk_bytes / sensor_bags;
    let files = write_grandtour(&a.out, mission, &options)?;
    if let Some(path) = &a.truth {
        write_json(path, &truth_json(mission))?;
    }
    eprintln!(
        "wrote {} ({} bags, {:.0} s)",
        a.out.display(),
        files.len(),
        mission.duration_s
    );
    Ok(EXIT_OK)
}

/// `--grandtour --multi-clock`: several sources on several clocks, as per-sensor bags.
fn multi_clock(a: &SimulateArgs, route: &[trajdrift::simulate::motion::Segment]) -> Result<u8> {
    use trajdrift::simulate::grandtour::{write_multi_clock, PRISM_TOPIC};
    use trajdrift::simulate::sources::{multi_clock_truth, simulate_sources, MultiClockConfig};
    let duration: f64 = route.iter().map(|s| s.duration_s).sum();
    let mission = simulate_sources(&MultiClockConfig::varied(a.seed, duration), route);
    let files = write_multi_clock(&a.out, &mission, a.merged)?;
    if let Some(path) = &a.truth {
        write_json(path, &multi_clock_truth(&mission, PRISM_TOPIC))?;
    }
    eprintln!(
        "wrote {} ({} bags, {} sources, {:.0} s)",
        a.out.display(),
        files.len(),
        mission.sources.len() + 1,
        mission.duration_s
    );
    Ok(EXIT_OK)
}

/// The longest mission simulated, seconds (six hours: longer than a robot's battery lasts).
pub const MAX_DURATION_S: f64 = 21_600.0;
/// The highest estimate rate, Hz (poses at IMU rate).
pub const MAX_EST_RATE_HZ: f64 = 1_000.0;
/// The most estimate samples one mission holds (about 640 MB of poses).
pub const MAX_EST_SAMPLES: f64 = 1.0e7;

/// Every number of the mission finite and in its range, before anything is simulated: a refusal
/// (a usage error) names the flag, the value and the range.
fn check_args(a: &SimulateArgs) -> trajdrift::Result<()> {
    use trajdrift::params::{Bound, Range, LEVER_RANGE};
    let range = |min: f64, max: f64, unit: &'static str| Range {
        min: Bound::Inclusive(min),
        max: Bound::Inclusive(max),
        unit,
    };
    range(-86_400.0, 86_400.0, "s").check("--time-offset", a.time_offset)?;
    range(-0.5, 0.5, "").check("--scale-error", a.scale_error)?;
    range(-1.0e4, 1.0e4, "ppm").check("--clock-drift-ppm", a.clock_drift_ppm)?;
    for (axis, v) in ["x", "y", "z"].iter().zip(a.lever) {
        LEVER_RANGE.check(&format!("--lever {axis}"), v)?;
    }
    Range {
        min: Bound::Exclusive(0.0),
        ..range(0.0, MAX_EST_RATE_HZ, "Hz")
    }
    .check("--est-rate", a.est_rate)?;
    let lap_s: f64 = default_route().iter().map(|s| s.duration_s).sum();
    let duration_s = match a.duration {
        Some(d) => range(1.0, MAX_DURATION_S, "s").check("--duration", d)?,
        None => {
            let most = (MAX_DURATION_S / lap_s).floor() as usize;
            if a.laps > most {
                return Err(trajdrift::Error::InvalidArgument(format!(
                    "--laps {}: out of range; expected at most {most} laps of {lap_s:.0} s (a mission of at most {MAX_DURATION_S:.0} s)",
                    a.laps
                )));
            }
            a.laps.max(1) as f64 * lap_s
        }
    };
    if duration_s * a.est_rate > MAX_EST_SAMPLES {
        return Err(trajdrift::Error::InvalidArgument(format!(
            "--est-rate {}: {duration_s:.0} s of estimate at this rate are {:.1e} samples (at most {MAX_EST_SAMPLES:.0e}); lower --est-rate, --duration or --laps",
            a.est_rate,
            duration_s * a.est_rate
        )));
    }
    Ok(())
}

/// Runs the command; returns the exit code.
pub fn run(a: SimulateArgs) -> Result<u8> {
    check_args(&a)?;
    if a.out.exists() && !a.force {
        return Err(anyhow!(trajdrift::Error::InvalidArgument(format!(
            "{}: exists; pass --force to replace it",
            a.out.display()
        ))));
    }
    if let Some(truth) = a.truth.as_ref().filter(|t| t.exists() && !a.force) {
        return Err(anyhow!(trajdrift::Error::InvalidArgument(format!(
            "--truth {}: exists; pass --force to replace it",
            truth.display()
        ))));
    }
    claim_outputs(&a)?;
    let config = MissionConfig {
        seed: a.seed,
        time_offset_s: a.time_offset,
        scale_error: a.scale_error,
        est_lever_m: a.lever,
        clock_drift_ppm: a.clock_drift_ppm,
        clock_step: a.clock_step,
        est_rate_hz: a.est_rate,
        ..MissionConfig::default()
    };
    let route: Vec<_> = match a.duration {
        Some(seconds) => route_of_duration(&default_route(), seconds),
        None => std::iter::repeat_n(default_route(), a.laps.max(1))
            .flatten()
            .collect(),
    };
    if a.multi_clock {
        return multi_clock(&a, &route);
    }
    let mission = simulate(&config, &route);
    let bulk_messages = (mission.duration_s * 10.0).max(1.0);
    let bulk_bytes = (a.bulk_mib as f64 * 1024.0 * 1024.0 / bulk_messages) as usize;
    if a.grandtour {
        return grandtour(&a, &mission, bulk_bytes);
    }
    let mut target = OutputFile::create(&a.out)?;
    let file = target
        .file()
        .try_clone()
        .map_err(|e| trajdrift::Error::output(&a.out, &e))?;
    write_mcap(std::io::BufWriter::new(file), &mission, bulk_bytes).map_err(|e| {
        anyhow!(trajdrift::Error::Output {
            path: a.out.clone(),
            detail: e.to_string(),
        })
    })?;
    target.commit()?;
    if let Some(path) = &a.truth {
        write_json(path, &truth_json(&mission))?;
    }
    eprintln!(
        "wrote {} ({:.0} s, {} reference and {} estimate samples)",
        a.out.display(),
        mission.duration_s,
        mission.reference.len(),
        mission.estimate.len()
    );
    Ok(EXIT_OK)
}

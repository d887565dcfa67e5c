//! `trajdrift simulate`: write a simulated mission with known truth (the project's own fixtures and the
//! memory benchmark's large recordings come from here).

use anyhow::{anyhow, Result};

use trajdrift::output::{write_output, AtomicFile};
use trajdrift::simulate::writer::{truth_json, write_mcap};
use trajdrift::simulate::{default_route, route_of_duration, simulate, MissionConfig};

use crate::cli::args::SimulateArgs;
use crate::cli::EXIT_OK;

/// `--grandtour`: the mission as a folder of per-sensor bags (the bulk split over the sensor bags).
fn grandtour(
    a: &SimulateArgs,
    mission: &trajdrift::simulate::Mission,
    bulk_bytes: usize,
) -> Result<u8> {
    use trajdrift::simulate::grandtour::{write_grandtour, GrandTourOptions};
    let mut options = GrandTourOptions {
        merged: a.merged,
        ..GrandTourOptions::default()
    };
    let sensor_bags = options.bags.len() - 1;
    options.bulk_bytes = bulk_bytes / sensor_bags;
    let files = write_grandtour(&a.out, mission, &options)?;
    if let Some(path) = &a.truth {
        let mut bytes = serde_json::to_vec_pretty(&truth_json(mission))?;
        bytes.push(b'\n');
        write_output(path, &bytes)?;
    }
    eprintln!(
        "wrote {} ({} bags, {:.0} s)",
        a.out.display(),
        files.len(),
        mission.duration_s
    );
    Ok(EXIT_OK)
}

/// Runs the command; returns the exit code.
pub fn run(a: SimulateArgs) -> Result<u8> {
    if a.out.exists() && !a.force {
        return Err(anyhow!(
            "{}: exists; pass --force to replace it",
            a.out.display()
        ));
    }
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
    let mission = simulate(&config, &route);
    let bulk_messages = (mission.duration_s * 10.0).max(1.0);
    let bulk_bytes = (a.bulk_mib as f64 * 1024.0 * 1024.0 / bulk_messages) as usize;
    if a.grandtour {
        return grandtour(&a, &mission, bulk_bytes);
    }
    let mut target = AtomicFile::create(&a.out)?;
    let file = target.file().try_clone()?;
    write_mcap(std::io::BufWriter::new(file), &mission, bulk_bytes)?;
    target.commit()?;
    if let Some(path) = &a.truth {
        let mut bytes = serde_json::to_vec_pretty(&truth_json(&mission))?;
        bytes.push(b'\n');
        write_output(path, &bytes)?;
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

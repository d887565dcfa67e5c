//! Simulated missions with known truth: a rigid body carrying a reference sensor and an estimate
//! sensor at a lever arm, an estimate with a distance scale error and a clock offset, noisy reference.
//!
//! The project's own fixtures (`fixtures/`) are written by this module (`trajdrift simulate`), so the
//! README's first command runs on data we can regenerate and whose truth we know.

pub mod grandtour;
pub mod like;
pub mod motion;
pub(crate) mod ros1_definitions;
pub mod scenario;
pub mod sources;
pub mod topics;
pub mod writer;

use nalgebra::{UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::trajectory::Trajectory;
use motion::{integrate, state_at, Segment};

/// Everything that defines a simulated mission.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MissionConfig {
    pub seed: u64,
    /// Stamp of the first sample, ns since the epoch.
    pub start_time_ns: i64,
    pub ref_rate_hz: f64,
    pub est_rate_hz: f64,
    /// White noise on each reference coordinate, metres (1σ).
    pub ref_noise_m: f64,
    /// White noise on each estimate coordinate, metres (1σ).
    pub est_noise_m: f64,
    /// Reference sensor position in the body frame (x forward, y left, z up), metres.
    pub ref_lever_m: [f64; 3],
    /// Estimate sensor position in the body frame, metres.
    pub est_lever_m: [f64; 3],
    /// Δt: estimate stamps + Δt = reference clock.
    pub time_offset_s: f64,
    /// The estimate's distance scale error (0.02 = 2 % too long).
    pub scale_error: f64,
    /// The estimate's clock rate error, ppm: its stamps read
    /// t0 + (t_true − t0)·(1 + ppm·10⁻⁶) − time_offset (t0 = `start_time_ns`), so Δt falls by ppm µs
    /// per second.
    pub clock_drift_ppm: f64,
    /// A step of the estimate's clock: from true time `at_s` on, Δt is `offset_s` instead of
    /// `time_offset_s` (a recorder restart, an NTP correction). Stamps stay increasing only when the
    /// step is forward or the recorder drops the repeated stretch: samples whose stamp would not
    /// increase are dropped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clock_step: Option<ClockStep>,
}

/// A step of the simulated estimate's clock.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClockStep {
    /// True time of the step, seconds from the start.
    pub at_s: f64,
    /// Δt from then on, seconds.
    pub offset_s: f64,
}

impl std::str::FromStr for ClockStep {
    type Err = String;

    /// `AT:OFFSET`: true time of the step (seconds from the start) and the Δt from then on.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad =
            || format!("takes AT:OFFSET (seconds from the start, then the new Δt), got `{s}`");
        let (at, offset) = s.split_once(':').ok_or_else(bad)?;
        let (at_s, offset_s) = (at.trim().parse::<f64>(), offset.trim().parse::<f64>());
        match (at_s, offset_s) {
            (Ok(at_s), Ok(offset_s)) if at_s.is_finite() && at_s >= 0.0 && offset_s.is_finite() => {
                Ok(ClockStep { at_s, offset_s })
            }
            _ => Err(bad()),
        }
    }
}

impl Default for MissionConfig {
    /// A small wheeled mission: 10 Hz reference with 2 cm noise, 20 Hz estimate 0.3 m to the left of
    /// it, 2 % scale error, Δt = +0.2 s.
    fn default() -> Self {
        MissionConfig {
            seed: 7,
            start_time_ns: 1_718_460_000_000_000_000,
            ref_rate_hz: 10.0,
            est_rate_hz: 20.0,
            ref_noise_m: 0.02,
            est_noise_m: 0.003,
            ref_lever_m: [0.0, 0.0, 0.0],
            est_lever_m: [0.0, 0.3, 0.0],
            time_offset_s: 0.2,
            scale_error: 0.02,
            clock_drift_ppm: 0.0,
            clock_step: None,
        }
    }
}

impl MissionConfig {
    /// The estimate's clock ([`sources::SourceClock`], the one stamping rule of every simulated source).
    pub fn clock(&self) -> sources::SourceClock {
        sources::SourceClock {
            offset_s: self.time_offset_s,
            drift_ppm: self.clock_drift_ppm,
            step: self.clock_step,
        }
    }
}

/// A simulated mission: what the sensors published, and the truth.
#[derive(Debug, Clone)]
pub struct Mission {
    pub config: MissionConfig,
    /// Reference positions (world ENU), stamped on the true clock.
    pub reference: Trajectory,
    /// Estimate poses in its own odometry frame (starts at the identity), stamped on its own clock.
    pub estimate: Trajectory,
    /// True path length of the body, metres.
    pub body_path_m: f64,
    pub duration_s: f64,
}

/// `lap` repeated, cut to last exactly `duration_s` seconds (the last segment shortened).
pub fn route_of_duration(lap: &[Segment], duration_s: f64) -> Vec<Segment> {
    let lap_s: f64 = lap.iter().map(|s| s.duration_s).sum();
    if lap.is_empty() || !(lap_s > 0.0 && duration_s > 0.0) {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut left = duration_s;
    for s in lap.iter().cycle() {
        if left <= 0.0 {
            break;
        }
        out.push(Segment {
            duration_s: s.duration_s.min(left),
            ..*s
        });
        left -= s.duration_s;
    }
    out
}

/// The default route: a stop, S-curves, loops left and right, straights, stops; about 150 s.
pub fn default_route() -> Vec<Segment> {
    let s = |d: f64, v: f64, k: f64| Segment {
        duration_s: d,
        speed_mps: v,
        curvature: k,
    };
    vec![
        s(3.0, 0.0, 0.0),
        s(12.0, 1.5, 0.0),
        s(10.0, 1.5, 0.15),
        s(6.0, 1.8, 0.0),
        s(12.0, 1.2, -0.25),
        s(8.0, 2.0, 0.0),
        s(3.0, 0.0, 0.0),
        s(10.0, 1.0, 0.3),
        s(10.0, 1.6, -0.1),
        s(12.0, 1.4, 0.2),
        s(8.0, 2.0, 0.0),
        s(14.0, 1.0, -0.35),
        s(10.0, 1.5, 0.05),
        s(3.0, 0.0, 0.0),
    ]
}

/// Simulates `config` on `route`.
pub fn simulate(config: &MissionConfig, route: &[Segment]) -> Mission {
    const RATE: f64 = 1000.0;
    let states = integrate(route, RATE, 0.4, 1.0);
    let duration_s = states.last().map_or(0.0, |s| s.t);
    let body_path_m = states
        .windows(2)
        .map(|w| (w[1].position - w[0].position).norm())
        .sum();
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    let lever = |l: [f64; 3]| Vector3::new(l[0], l[1], l[2]);
    let sensor = |t: f64, l: &Vector3<f64>| {
        let s = state_at(&states, RATE, t);
        let r = UnitQuaternion::from_euler_angles(0.0, 0.0, s.yaw);
        (s.position + r * l, r)
    };

    let mut reference = Trajectory::new(false);
    let ref_lever = lever(config.ref_lever_m);
    let n_ref = (duration_s * config.ref_rate_hz).floor() as usize + 1;
    for i in 0..n_ref {
        let t = i as f64 / config.ref_rate_hz;
        let (p, _) = sensor(t, &ref_lever);
        let noise = white(&mut rng, config.ref_noise_m);
        reference.push(
            config.start_time_ns + (t * 1e9).round() as i64,
            p + noise,
            None,
        );
    }

    // The estimate: increments of its sensor's true path, scaled, in a frame that starts at the identity.
    let mut estimate = Trajectory::new(true);
    let est_lever = lever(config.est_lever_m);
    let (p0, r0) = sensor(0.0, &est_lever);
    let n_est = (duration_s * config.est_rate_hz).floor() as usize + 1;
    for i in 0..n_est {
        let t_true = i as f64 / config.est_rate_hz;
        let (p, r) = sensor(t_true, &est_lever);
        let local = r0.inverse() * (p - p0) * (1.0 + config.scale_error);
        let noise = white(&mut rng, config.est_noise_m);
        let stamp = config.clock().stamp_ns(config.start_time_ns, t_true);
        if estimate.stamps_ns.last().is_some_and(|&last| stamp <= last) {
            continue;
        }
        estimate.push(stamp, local + noise, Some(r0.inverse() * r));
    }
    Mission {
        config: config.clone(),
        reference,
        estimate,
        body_path_m,
        duration_s,
    }
}

/// Three independent Gaussian samples of standard deviation `sigma`.
pub(crate) fn white(rng: &mut ChaCha8Rng, sigma: f64) -> Vector3<f64> {
    let mut g = || -> f64 { StandardNormal.sample(rng) };
    Vector3::new(g(), g(), g()) * sigma
}

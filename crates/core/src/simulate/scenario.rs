//! Varied missions for validation: every kind of mission the time alignment must handle, drawn from a
//! seed, with the truth to grade the answer against.
//!
//! [`crate::simulate::simulate`] writes the project's fixtures: one planar route, one lever arm, a
//! 1 kHz body without attitude. A tool whose error bars are to mean something must be graded on more
//! than that, so this module draws a mission of a named [`MissionKind`] from a seed:
//!
//! - **the body**: a wheeled robot (0.8–2 m/s, gentle curves) or a legged one (0.25–0.5 m/s, tight
//!   turns, a trotting gait: lateral sway, vertical bob, roll and pitch at 1.5–2.5 Hz while it moves),
//!   driving stops, straights, arcs and S-curves with bounded acceleration and yaw acceleration,
//!   optionally turning in place, over rolling terrain that tilts the body;
//! - **the sensors**: a reference (GNSS, prism) at 1–20 Hz with white noise and a slow correlated error,
//!   and an estimate (odometry) at 10–200 Hz, each at its own 3-D lever arm in the body frame
//!   (vertical levers included), so that every roll, pitch and turn in place moves them apart;
//! - **the estimate's errors**: a distance scale error, a heading random walk (its positions drift as
//!   integrated odometry does), white position and attitude noise, and optionally position jumps (a
//!   localiser correcting itself: not clock events);
//! - **the clocks**: a constant offset, a rate error (ppm), or a step; stamps taken at receipt (a
//!   latency with exponential jitter on each stream) where the kind says so; GNSS outages.
//!
//! Every random choice comes from one ChaCha8 stream seeded by `seed`, so a mission is reproduced from
//! its kind and seed alone. The truth is the offset function Δt(t) ([`Scenario::offset_at`]): the
//! estimate's stamps plus Δt(t) give the reference clock at reference time t, the mean receipt
//! latencies included (a constant latency is part of the offset a user must apply).

use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Exp, StandardNormal};

use crate::simulate::ClockStep;
use crate::trajectory::Trajectory;

/// What a validation mission exercises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MissionKind {
    /// A wheeled robot, levers up to 0.5 m (vertical ones included), constant clock.
    Ground,
    /// A legged robot with a trotting gait and a lever (often the sensor ahead of and above the
    /// reference point), constant clock.
    Legged,
    /// A wheeled robot driving nearly straight: the curvature cannot tell, the speed changes can.
    NearStraight,
    /// A legged robot that turns in place: the reference point stands while a sensor at a lever
    /// sweeps an arc.
    TurnsInPlace,
    /// GNSS outages of 5–20 s in the reference.
    GnssOutages,
    /// Both streams stamped at receipt: a latency with exponential jitter on each.
    ReceiptStamps,
    /// The estimate's position jumps (a localiser correcting itself) two or three times.
    PositionJumps,
    /// A 15–25-minute mission (wheeled or legged) whose estimate clock runs ±40…150 ppm off.
    Drift,
    /// A 5-minute mission whose estimate clock runs 50 ppm off (about what the data resolve).
    ShortDrift,
    /// The estimate's clock steps by 0.1–1 s once, in the middle half of an 8–12-minute mission.
    Step,
}

impl MissionKind {
    /// Every kind, in the order the validation table lists them.
    pub const ALL: [MissionKind; 10] = [
        MissionKind::Ground,
        MissionKind::Legged,
        MissionKind::NearStraight,
        MissionKind::TurnsInPlace,
        MissionKind::GnssOutages,
        MissionKind::ReceiptStamps,
        MissionKind::PositionJumps,
        MissionKind::Drift,
        MissionKind::ShortDrift,
        MissionKind::Step,
    ];

    /// The name as on the command line and in tables.
    pub fn as_str(self) -> &'static str {
        match self {
            MissionKind::Ground => "ground",
            MissionKind::Legged => "legged",
            MissionKind::NearStraight => "near_straight",
            MissionKind::TurnsInPlace => "turns_in_place",
            MissionKind::GnssOutages => "gnss_outages",
            MissionKind::ReceiptStamps => "receipt_stamps",
            MissionKind::PositionJumps => "position_jumps",
            MissionKind::Drift => "drift",
            MissionKind::ShortDrift => "short_drift",
            MissionKind::Step => "step",
        }
    }

    /// Whether the kind's clock is one constant offset.
    pub fn constant_clock(self) -> bool {
        !matches!(
            self,
            MissionKind::Drift | MissionKind::ShortDrift | MissionKind::Step
        )
    }
}

impl std::str::FromStr for MissionKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        MissionKind::ALL
            .iter()
            .copied()
            .find(|k| k.as_str() == s.replace('-', "_"))
            .ok_or_else(|| {
                let names: Vec<&str> = MissionKind::ALL.iter().map(|k| k.as_str()).collect();
                format!(
                    "unknown mission kind `{s}`; expected one of {}",
                    names.join(", ")
                )
            })
    }
}

/// One leg of a route: driven at a target speed and curvature, or (speed 0, `spin_rps` ≠ 0) a turn
/// in place.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Leg {
    pub duration_s: f64,
    pub speed_mps: f64,
    /// Path curvature, 1/m (positive: left).
    pub curvature: f64,
    /// Yaw rate of a turn in place, rad/s (used when the speed is 0).
    pub spin_rps: f64,
}

/// A legged robot's gait, while it moves.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Gait {
    pub frequency_hz: f64,
    /// Lateral sway amplitude, metres.
    pub sway_m: f64,
    /// Vertical bob amplitude (at twice the frequency), metres.
    pub bob_m: f64,
    /// Roll amplitude, radians.
    pub roll_rad: f64,
    /// Pitch amplitude (at twice the frequency), radians.
    pub pitch_rad: f64,
}

/// Everything that defines a validation mission (drawn by [`Scenario::draw`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Scenario {
    pub kind: MissionKind,
    pub seed: u64,
    pub legged: bool,
    pub route: Vec<Leg>,
    pub gait: Option<Gait>,
    /// Amplitude of the rolling terrain, metres (slopes of a few degrees).
    pub terrain_m: f64,
    pub ref_rate_hz: f64,
    pub est_rate_hz: f64,
    /// White noise per reference coordinate, metres.
    pub ref_noise_m: f64,
    /// A slow (Gauss–Markov, 30 s) error per reference coordinate, metres.
    pub ref_slow_noise_m: f64,
    /// White noise per estimate coordinate, metres; attitude noise, radians.
    pub est_noise_m: f64,
    pub est_attitude_noise_rad: f64,
    /// Sensor positions in the body frame (x forward, y left, z up), metres.
    pub ref_lever_m: [f64; 3],
    pub est_lever_m: [f64; 3],
    /// Δt at the start: estimate stamps + Δt = reference clock.
    pub time_offset_s: f64,
    /// The estimate clock's rate error, ppm (positive: it runs fast, Δt falls).
    pub clock_drift_ppm: f64,
    pub clock_step: Option<ClockStep>,
    /// The estimate's distance scale error (0.02: 2 % long).
    pub scale_error: f64,
    /// The estimate's heading random walk, degrees per √s.
    pub yaw_walk_deg_per_sqrt_s: f64,
    /// Reference outages, true seconds from the start.
    pub outages: Vec<(f64, f64)>,
    /// Receipt stamps: mean latency of the reference's and of the estimate's stamps (exponential), s.
    pub receipt_latency_s: Option<(f64, f64)>,
    /// Position jumps of the estimate: (true time, jump in its frame, metres).
    pub jumps: Vec<(f64, [f64; 3])>,
}

/// A drawn mission: the scenario, what the sensors published, and how long it lasted.
#[derive(Debug, Clone)]
pub struct ScenarioMission {
    pub scenario: Scenario,
    /// Reference positions (world ENU), stamped on the reference clock (ns since the epoch).
    pub reference: Trajectory,
    /// Estimate poses in its own frame, stamped on its own clock.
    pub estimate: Trajectory,
    pub duration_s: f64,
}

/// Stamp of the first sample, ns since the epoch.
pub const START_NS: i64 = 1_718_460_000_000_000_000;

/// Rate of the body's integration, Hz.
const BODY_RATE_HZ: f64 = 1000.0;

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

fn pick<T: Copy>(rng: &mut ChaCha8Rng, v: &[T]) -> T {
    v[rng.random_range(0..v.len())]
}

fn signed(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let m = uniform(rng, lo, hi);
    if rng.random::<bool>() {
        m
    } else {
        -m
    }
}

impl Scenario {
    /// The mission of `kind` drawn from `seed` (see the module doc for the ranges).
    ///
    /// Every draw takes the next numbers of one stream, so the order of the draws below is part of
    /// the mission: reordering them changes every mission of every seed.
    pub fn draw(kind: MissionKind, seed: u64) -> Scenario {
        // The kind enters the stream too: seed 3 of two kinds are unrelated missions.
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ ((kind as u64 + 1) << 40));
        let rng = &mut rng;
        let legged = draw_legged(rng, kind, seed);
        let duration_s = draw_duration_s(rng, kind);
        let route = draw_route(rng, legged, kind, spin_share(kind, legged), duration_s);
        let gait = legged.then(|| Gait::draw(rng));
        let (ref_rate_hz, est_rate_hz) = draw_rates_hz(rng, legged);
        let est_lever_m = draw_est_lever_m(rng, legged);
        let ref_lever_m = draw_ref_lever_m(rng);
        let outages = draw_outages(rng, kind, duration_s);
        let receipt_latency_s =
            (kind == MissionKind::ReceiptStamps).then(|| draw_receipt_latency_s(rng));
        let jumps = if kind == MissionKind::PositionJumps {
            draw_jumps(rng, duration_s)
        } else {
            Vec::new()
        };
        let clock = EstimateClock::draw(rng, kind, duration_s);
        let noise = Noise::draw(rng, legged);
        Scenario {
            kind,
            seed,
            legged,
            route,
            gait,
            terrain_m: noise.terrain_m,
            ref_rate_hz,
            est_rate_hz,
            ref_noise_m: noise.ref_noise_m,
            ref_slow_noise_m: noise.ref_slow_noise_m,
            est_noise_m: noise.est_noise_m,
            est_attitude_noise_rad: noise.est_attitude_noise_rad,
            ref_lever_m,
            est_lever_m,
            time_offset_s: clock.time_offset_s,
            clock_drift_ppm: clock.drift_ppm,
            clock_step: clock.step,
            scale_error: noise.scale_error,
            yaw_walk_deg_per_sqrt_s: noise.yaw_walk_deg_per_sqrt_s,
            outages,
            receipt_latency_s,
            jumps,
        }
    }

    /// The mission's length, seconds.
    pub fn duration_s(&self) -> f64 {
        self.route.iter().map(|l| l.duration_s).sum()
    }

    /// Δt at reference time `t` (seconds from the start): the estimate's stamp of the instant t plus
    /// Δt(t) is t on the reference clock (mean receipt latencies included).
    pub fn offset_at(&self, t: f64) -> f64 {
        let base = match self.clock_step {
            Some(s) if t >= s.at_s => s.offset_s,
            _ => self.time_offset_s,
        };
        let latency = self.receipt_latency_s.map_or(0.0, |(r, e)| r - e);
        base - self.clock_drift_ppm * 1e-6 * t + latency
    }

    /// Simulates the scenario.
    pub fn simulate(&self) -> ScenarioMission {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 1);
        let body = Body::integrate(self);
        let duration_s = body.duration_s();
        let lever = |l: [f64; 3]| Vector3::new(l[0], l[1], l[2]);
        let (ref_lever, est_lever) = (lever(self.ref_lever_m), lever(self.est_lever_m));
        let (ref_latency, est_latency) = self.receipt_latencies();
        // One stream of draws: the reference's first, then the estimate's.
        let reference = self.sample_reference(&mut rng, &body, &ref_lever, ref_latency);
        let estimate = self.sample_estimate(&mut rng, &body, &est_lever, est_latency);
        ScenarioMission {
            scenario: self.clone(),
            reference,
            estimate,
            duration_s,
        }
    }

    /// The exponential receipt latencies of the reference's and of the estimate's stamps (none
    /// without receipt stamps, or at a mean of 0).
    fn receipt_latencies(&self) -> (Option<Exp<f64>>, Option<Exp<f64>>) {
        let exp = |mean: f64| (mean > 0.0).then(|| Exp::new(1.0 / mean).ok()).flatten();
        self.receipt_latency_s
            .map_or((None, None), |(r, e)| (exp(r), exp(e)))
    }

    /// The reference: its sensor's positions at its rate from a random phase, with white noise plus
    /// a first-order Gauss–Markov error (τ = 30 s), stamped at receipt when `latency` is given. In
    /// an outage nothing is published, but the sample's noise is still drawn.
    fn sample_reference(
        &self,
        rng: &mut ChaCha8Rng,
        body: &Body,
        lever: &Vector3<f64>,
        latency: Option<Exp<f64>>,
    ) -> Trajectory {
        let duration_s = body.duration_s();
        let mut reference = Trajectory::new(false);
        let ref_phase = rng.random::<f64>() / self.ref_rate_hz;
        let n_ref = ((duration_s - ref_phase) * self.ref_rate_hz).floor() as usize + 1;
        let tau = 30.0;
        let mut slow = Vector3::zeros();
        for i in 0..n_ref {
            let t = ref_phase + i as f64 / self.ref_rate_hz;
            let a = (-1.0 / (self.ref_rate_hz * tau)).exp();
            slow = slow * a + white(rng, self.ref_slow_noise_m * (1.0 - a * a).sqrt());
            let noise = white(rng, self.ref_noise_m);
            let late = latency.map_or(0.0, |d| d.sample(rng));
            if self.outages.iter().any(|&(a, b)| t >= a && t <= b) {
                continue;
            }
            let (p, _) = body.sensor(t, lever);
            reference.push(
                START_NS + ((t + late) * 1e9).round() as i64,
                p + noise + slow,
                None,
            );
        }
        reference.sort_dedup();
        reference
    }

    /// The estimate: increments of its sensor's true path, scaled and turned by a heading random
    /// walk, in a gravity-aligned frame that starts at its sensor with the body's heading; with its
    /// position jumps, white position and attitude noise, stamped on its own clock
    /// ([`Scenario::estimate_stamp_ns`]).
    fn sample_estimate(
        &self,
        rng: &mut ChaCha8Rng,
        body: &Body,
        lever: &Vector3<f64>,
        latency: Option<Exp<f64>>,
    ) -> Trajectory {
        let duration_s = body.duration_s();
        let mut estimate = Trajectory::new(true);
        let est_phase = rng.random::<f64>() / self.est_rate_hz;
        let n_est = ((duration_s - est_phase) * self.est_rate_hz).floor() as usize + 1;
        let (p0, _) = body.sensor(est_phase, lever);
        let frame = Rotation3::from_axis_angle(&Vector3::z_axis(), -body.yaw_at(est_phase));
        let walk = self.yaw_walk_deg_per_sqrt_s.to_radians() / self.est_rate_hz.sqrt();
        let (mut yaw_err, mut pos, mut last) = (0.0f64, Vector3::zeros(), p0);
        let mut jumped = Vector3::zeros();
        let mut jumps = self.jumps.clone();
        jumps.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut next_jump = 0;
        for j in 0..n_est {
            let t = est_phase + j as f64 / self.est_rate_hz;
            let (p, r) = body.sensor(t, lever);
            let drift = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw_err);
            pos += drift * (frame * (p - last)) * (1.0 + self.scale_error);
            last = p;
            yaw_err += walk * gauss(rng);
            while next_jump < jumps.len() && jumps[next_jump].0 <= t {
                let d = jumps[next_jump].1;
                jumped += Vector3::new(d[0], d[1], d[2]);
                next_jump += 1;
            }
            let attitude = Rotation3::new(white(rng, self.est_attitude_noise_rad));
            let orientation = drift * frame * r * attitude;
            let noise = white(rng, self.est_noise_m);
            let late = latency.map_or(0.0, |d| d.sample(rng));
            estimate.push(
                self.estimate_stamp_ns(t, late),
                pos + jumped + noise,
                Some(UnitQuaternion::from_rotation_matrix(&orientation)),
            );
        }
        // A backward clock step repeats a stretch of stamps: the recorder keeps them in order.
        estimate.sort_dedup();
        estimate
    }

    /// The estimate's stamp of true time `t` (seconds from the start), ns since the epoch: its clock
    /// (rate error, then the offset or the step) plus a receipt latency `late_s`.
    fn estimate_stamp_ns(&self, t: f64, late_s: f64) -> i64 {
        let t_clock = t * (1.0 + self.clock_drift_ppm * 1e-6);
        let offset = match self.clock_step {
            Some(s) if t >= s.at_s => s.offset_s,
            _ => self.time_offset_s,
        };
        START_NS + ((t_clock - offset + late_s) * 1e9).round() as i64
    }
}

/// Whether the robot walks: always for the legged kinds, never nearly straight, by the seed's parity
/// for the clock kinds (so their seeds alternate platforms), else 30 % of missions (one draw).
fn draw_legged(rng: &mut ChaCha8Rng, kind: MissionKind, seed: u64) -> bool {
    match kind {
        MissionKind::Legged | MissionKind::TurnsInPlace => true,
        MissionKind::Drift | MissionKind::ShortDrift | MissionKind::Step => seed % 2 == 1,
        MissionKind::NearStraight => false,
        _ => rng.random::<f64>() < 0.3,
    }
}

/// The mission's length, seconds: 15–25 minutes for a drift, 5 for a short drift, 8–12 for a step,
/// else 3–8 minutes.
fn draw_duration_s(rng: &mut ChaCha8Rng, kind: MissionKind) -> f64 {
    match kind {
        MissionKind::Drift => uniform(rng, 900.0, 1500.0),
        MissionKind::ShortDrift => 300.0,
        MissionKind::Step => uniform(rng, 480.0, 720.0),
        _ => uniform(rng, 180.0, 480.0),
    }
}

/// The share of the route's legs that are turns in place (no draw).
fn spin_share(kind: MissionKind, legged: bool) -> f64 {
    match kind {
        MissionKind::TurnsInPlace => 0.25,
        _ if legged => 0.05,
        _ => 0.0,
    }
}

impl Gait {
    /// A trotting gait: 1.5–2.5 Hz, centimetre sway and bob, a degree or two of roll and pitch.
    fn draw(rng: &mut ChaCha8Rng) -> Gait {
        Gait {
            frequency_hz: uniform(rng, 1.5, 2.5),
            sway_m: uniform(rng, 0.005, 0.02),
            bob_m: uniform(rng, 0.003, 0.008),
            roll_rad: uniform(rng, 0.5, 2.0).to_radians(),
            pitch_rad: uniform(rng, 0.3, 1.5).to_radians(),
        }
    }
}

/// The reference's and the estimate's rates, Hz (a legged robot's reference is a prism or an INS,
/// never a 1 Hz GNSS).
fn draw_rates_hz(rng: &mut ChaCha8Rng, legged: bool) -> (f64, f64) {
    let ref_rate_hz = if legged {
        pick(rng, &[5.0, 10.0, 10.0, 20.0, 20.0])
    } else {
        pick(rng, &[1.0, 2.0, 5.0, 10.0, 10.0, 20.0])
    };
    let est_rate_hz = pick(rng, &[10.0, 20.0, 50.0, 100.0, 200.0]);
    (ref_rate_hz, est_rate_hz)
}

/// The estimate sensor's lever arm in the body frame, metres (vertical ones included).
fn draw_est_lever_m(rng: &mut ChaCha8Rng, legged: bool) -> [f64; 3] {
    if legged {
        if rng.random::<f64>() < 0.35 {
            // A mounting once reported with a false clock step: 0.2 m ahead, 0.3 m above.
            [0.2, 0.0, 0.3]
        } else {
            [
                uniform(rng, -0.3, 0.3),
                uniform(rng, -0.2, 0.2),
                uniform(rng, 0.0, 0.4),
            ]
        }
    } else {
        [
            uniform(rng, -0.5, 0.5),
            uniform(rng, -0.5, 0.5),
            uniform(rng, 0.0, 0.5),
        ]
    }
}

/// The reference sensor's lever arm, metres: at the body's point in 70 % of missions, else a mast.
fn draw_ref_lever_m(rng: &mut ChaCha8Rng) -> [f64; 3] {
    if rng.random::<f64>() < 0.3 {
        [
            uniform(rng, -0.2, 0.2),
            uniform(rng, -0.2, 0.2),
            uniform(rng, 0.2, 0.8),
        ]
    } else {
        [0.0; 3]
    }
}

/// Reference outages of 5–20 s, true seconds from the start: two to four for the outage kind, one
/// in 10 % of the other missions.
fn draw_outages(rng: &mut ChaCha8Rng, kind: MissionKind, duration_s: f64) -> Vec<(f64, f64)> {
    let outage_count = match kind {
        MissionKind::GnssOutages => rng.random_range(2..=4),
        _ if rng.random::<f64>() < 0.1 => 1,
        _ => 0,
    };
    let mut outages = Vec::new();
    for _ in 0..outage_count {
        let len = uniform(rng, 5.0, 20.0);
        let at = uniform(rng, 20.0, (duration_s - len - 20.0).max(21.0));
        outages.push((at, at + len));
    }
    outages
}

/// The mean receipt latencies of the reference's and of the estimate's stamps, seconds.
fn draw_receipt_latency_s(rng: &mut ChaCha8Rng) -> (f64, f64) {
    (uniform(rng, 0.005, 0.03), uniform(rng, 0.001, 0.01))
}

/// Two or three position jumps of the estimate (a localiser correcting itself): true time, and a
/// jump of 0.3–2 m in its frame.
fn draw_jumps(rng: &mut ChaCha8Rng, duration_s: f64) -> Vec<(f64, [f64; 3])> {
    (0..rng.random_range(2..=3))
        .map(|_| {
            let size = uniform(rng, 0.3, 2.0);
            let dir = uniform(rng, 0.0, std::f64::consts::TAU);
            (
                uniform(rng, 30.0, duration_s - 30.0),
                [size * dir.cos(), size * dir.sin(), uniform(rng, -0.1, 0.1)],
            )
        })
        .collect()
}

/// The estimate's clock as drawn: its rate error, its Δt at the start and its step.
struct EstimateClock {
    drift_ppm: f64,
    time_offset_s: f64,
    step: Option<ClockStep>,
}

impl EstimateClock {
    /// The clock of `kind`: a rate error for the drift kinds, a step of 0.1–1 s in the middle of a
    /// step mission, a Δt of ±2 s for every mission.
    fn draw(rng: &mut ChaCha8Rng, kind: MissionKind, duration_s: f64) -> EstimateClock {
        let drift_ppm = match kind {
            MissionKind::Drift => signed(rng, 40.0, 150.0),
            MissionKind::ShortDrift => {
                if rng.random::<bool>() {
                    50.0
                } else {
                    -50.0
                }
            }
            _ => 0.0,
        };
        let time_offset_s = uniform(rng, -2.0, 2.0);
        let step = (kind == MissionKind::Step).then(|| ClockStep {
            at_s: uniform(rng, 0.3, 0.7) * duration_s,
            offset_s: time_offset_s + signed(rng, 0.1, 1.0),
        });
        EstimateClock {
            drift_ppm,
            time_offset_s,
            step,
        }
    }
}

/// The terrain and the sensors' errors, drawn last (in this field order).
struct Noise {
    terrain_m: f64,
    ref_noise_m: f64,
    ref_slow_noise_m: f64,
    est_noise_m: f64,
    est_attitude_noise_rad: f64,
    scale_error: f64,
    yaw_walk_deg_per_sqrt_s: f64,
}

impl Noise {
    /// Rolling terrain (rougher where a legged robot walks), the reference's white and slow noise,
    /// the estimate's white position and attitude noise, scale error and heading random walk.
    fn draw(rng: &mut ChaCha8Rng, legged: bool) -> Noise {
        let terrain_m = if legged {
            uniform(rng, 0.0, 1.0)
        } else {
            uniform(rng, 0.0, 0.5)
        };
        Noise {
            terrain_m,
            ref_noise_m: uniform(rng, 0.005, 0.03),
            ref_slow_noise_m: uniform(rng, 0.0, 0.01),
            est_noise_m: uniform(rng, 0.001, 0.005),
            est_attitude_noise_rad: uniform(rng, 0.02, 0.1).to_radians(),
            scale_error: uniform(rng, -0.03, 0.03),
            yaw_walk_deg_per_sqrt_s: uniform(rng, 0.02, 0.1),
        }
    }
}

/// A route of `duration_s` seconds for the kind (see the module doc).
fn draw_route(
    rng: &mut ChaCha8Rng,
    legged: bool,
    kind: MissionKind,
    spins: f64,
    duration_s: f64,
) -> Vec<Leg> {
    let leg = |d: f64, v: f64, k: f64| Leg {
        duration_s: d,
        speed_mps: v,
        curvature: k,
        spin_rps: 0.0,
    };
    let mut route = vec![leg(uniform(rng, 2.0, 4.0), 0.0, 0.0)];
    let mut total = route[0].duration_s;
    let straight = kind == MissionKind::NearStraight;
    while total < duration_s {
        let u: f64 = rng.random();
        let next = if u < spins {
            let rate = signed(rng, 0.3, 0.8);
            let angle = uniform(rng, 60f64.to_radians(), 360f64.to_radians());
            vec![
                Leg {
                    duration_s: angle / rate.abs(),
                    speed_mps: 0.0,
                    curvature: 0.0,
                    spin_rps: rate,
                },
                leg(uniform(rng, 1.0, 3.0), 0.0, 0.0),
            ]
        } else if u < spins + if straight { 0.06 } else { 0.12 } {
            vec![leg(uniform(rng, 2.0, 6.0), 0.0, 0.0)]
        } else {
            let (v, k) = if legged {
                (uniform(rng, 0.25, 0.5), signed(rng, 0.1, 1.2))
            } else if straight {
                (uniform(rng, 0.5, 2.0), signed(rng, 0.0, 0.008))
            } else {
                (uniform(rng, 0.8, 2.0), signed(rng, 0.05, 0.4))
            };
            match rng.random_range(0..3) {
                0 => vec![leg(
                    uniform(rng, 5.0, 20.0),
                    v,
                    if straight { k } else { 0.0 },
                )],
                1 => vec![leg(uniform(rng, 5.0, 15.0), v, k)],
                _ => {
                    let d = uniform(rng, 4.0, 10.0);
                    vec![leg(d, v, k), leg(d, v, -k)]
                }
            }
        };
        for l in next {
            total += l.duration_s;
            route.push(l);
        }
    }
    route.push(leg(uniform(rng, 2.0, 4.0), 0.0, 0.0));
    // Cut to the duration (the final stop kept).
    let mut out = Vec::new();
    let mut left = duration_s;
    let last = route.pop();
    for l in route {
        if left <= 0.0 {
            break;
        }
        out.push(Leg {
            duration_s: l.duration_s.min(left),
            ..l
        });
        left -= l.duration_s;
    }
    out.extend(last);
    out
}

/// The body's planar motion at [`BODY_RATE_HZ`], with the terrain and the gait it is drawn on.
struct Body {
    /// (x, y, yaw, activity in [0, 1]) per step.
    states: Vec<[f64; 4]>,
    gait: Option<Gait>,
    terrain: Terrain,
}

/// Rolling terrain: a sum of two sinusoidal ridges.
#[derive(Clone, Copy)]
struct Terrain {
    amplitude: f64,
    k1: [f64; 2],
    k2: [f64; 2],
    phase: [f64; 2],
}

impl Terrain {
    fn height(&self, x: f64, y: f64) -> f64 {
        self.amplitude
            * ((self.k1[0] * x + self.k1[1] * y + self.phase[0]).sin()
                + 0.5 * (self.k2[0] * x + self.k2[1] * y + self.phase[1]).sin())
    }

    /// ∂h/∂x, ∂h/∂y.
    fn gradient(&self, x: f64, y: f64) -> (f64, f64) {
        let c1 = self.amplitude * (self.k1[0] * x + self.k1[1] * y + self.phase[0]).cos();
        let c2 = 0.5 * self.amplitude * (self.k2[0] * x + self.k2[1] * y + self.phase[1]).cos();
        (
            c1 * self.k1[0] + c2 * self.k2[0],
            c1 * self.k1[1] + c2 * self.k2[1],
        )
    }
}

impl Body {
    /// Speed follows each leg with bounded acceleration, the yaw rate with bounded yaw acceleration.
    fn integrate(s: &Scenario) -> Body {
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed.wrapping_add(0x5151));
        let (accel, yaw_accel) = if s.legged { (0.5, 1.5) } else { (1.0, 0.6) };
        let dt = 1.0 / BODY_RATE_HZ;
        let total = s.duration_s();
        let n = (total * BODY_RATE_HZ).round() as usize + 1;
        let mut states = Vec::with_capacity(n);
        let (mut x, mut y) = (0.0f64, 0.0f64);
        let mut yaw: f64 = uniform(&mut rng, -3.1, 3.1);
        let (mut v, mut w) = (0.0f64, 0.0f64);
        let mut legs = s.route.iter();
        let mut leg = Leg {
            duration_s: 0.0,
            speed_mps: 0.0,
            curvature: 0.0,
            spin_rps: 0.0,
        };
        let mut leg_end = 0.0;
        for i in 0..n {
            let t = i as f64 * dt;
            while t >= leg_end - 1e-12 {
                match legs.next() {
                    Some(l) => {
                        leg = *l;
                        leg_end += l.duration_s;
                    }
                    None => {
                        leg.speed_mps = 0.0;
                        leg.spin_rps = 0.0;
                        leg_end = f64::INFINITY;
                    }
                }
            }
            let activity = (v / 0.15 + w.abs() / 0.3).min(1.0);
            states.push([x, y, yaw, activity]);
            v += (leg.speed_mps - v).clamp(-accel * dt, accel * dt);
            let w_target = if leg.speed_mps > 0.0 {
                v * leg.curvature
            } else {
                leg.spin_rps
            };
            w += (w_target - w).clamp(-yaw_accel * dt, yaw_accel * dt);
            yaw += w * dt;
            x += yaw.cos() * v * dt;
            y += yaw.sin() * v * dt;
        }
        let wave = |rng: &mut ChaCha8Rng| {
            let k = std::f64::consts::TAU / uniform(rng, 15.0, 40.0);
            let dir = uniform(rng, 0.0, std::f64::consts::TAU);
            [k * dir.cos(), k * dir.sin()]
        };
        let terrain = Terrain {
            amplitude: s.terrain_m,
            k1: wave(&mut rng),
            k2: wave(&mut rng),
            phase: [uniform(&mut rng, 0.0, 6.3), uniform(&mut rng, 0.0, 6.3)],
        };
        Body {
            states,
            gait: s.gait,
            terrain,
        }
    }

    fn duration_s(&self) -> f64 {
        (self.states.len() - 1) as f64 / BODY_RATE_HZ
    }

    /// The planar state at `t`, linearly interpolated.
    fn planar(&self, t: f64) -> [f64; 4] {
        let x = (t * BODY_RATE_HZ).clamp(0.0, (self.states.len() - 1) as f64);
        let i = (x.floor() as usize).min(self.states.len().saturating_sub(2));
        let f = x - i as f64;
        let (a, b) = (
            self.states[i],
            self.states[(i + 1).min(self.states.len() - 1)],
        );
        std::array::from_fn(|k| a[k] + (b[k] - a[k]) * f)
    }

    fn yaw_at(&self, t: f64) -> f64 {
        self.planar(t)[2]
    }

    /// The position of a sensor at `lever` (body frame) and the body's attitude, at `t`.
    fn sensor(&self, t: f64, lever: &Vector3<f64>) -> (Vector3<f64>, Rotation3<f64>) {
        let [x, y, yaw, activity] = self.planar(t);
        // The body's up axis along the terrain's normal, its forward axis the heading on the slope.
        let (gx, gy) = self.terrain.gradient(x, y);
        let up = Vector3::new(-gx, -gy, 1.0).normalize();
        let heading = Vector3::new(yaw.cos(), yaw.sin(), 0.0);
        let forward = (heading - up * heading.dot(&up)).normalize();
        let left = up.cross(&forward);
        let mut attitude =
            Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_columns(&[forward, left, up]));
        let mut p = Vector3::new(x, y, self.terrain.height(x, y));
        if let Some(g) = self.gait {
            let phase = std::f64::consts::TAU * g.frequency_hz * t;
            let sway = g.sway_m * phase.sin() * activity;
            let bob = g.bob_m * (2.0 * phase).sin() * activity;
            p += attitude * Vector3::new(0.0, sway, bob);
            let roll = g.roll_rad * (phase + 0.7).sin() * activity;
            let pitch = g.pitch_rad * (2.0 * phase + 1.3).sin() * activity;
            attitude *= Rotation3::from_euler_angles(roll, pitch, 0.0);
        }
        (p + attitude * lever, attitude)
    }
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// Three independent Gaussian samples of standard deviation `sigma`.
fn white(rng: &mut ChaCha8Rng, sigma: f64) -> Vector3<f64> {
    Vector3::new(gauss(rng), gauss(rng), gauss(rng)) * sigma
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A drawn mission is reproduced from its kind and seed, and its streams follow the truth: the
    /// estimate's stamps plus Δt(t) land on the reference clock.
    #[test]
    fn missions_are_reproducible_and_follow_their_truth() {
        for kind in MissionKind::ALL {
            let a = Scenario::draw(kind, 3);
            assert_eq!(a, Scenario::draw(kind, 3), "{kind:?}");
            assert!(
                (a.duration_s() - a.route.iter().map(|l| l.duration_s).sum::<f64>()).abs() < 1e-9
            );
        }
        let s = Scenario::draw(MissionKind::Ground, 5);
        let m = s.simulate();
        assert!(m.reference.len() > 100 && m.estimate.len() > 100);
        // Constant clock, no latency: the estimate's stamps plus Δt are its sampling instants, a
        // regular grid starting within one period of the reference's start.
        let period = 1.0 / s.est_rate_hz;
        let on_ref: Vec<f64> = m
            .estimate
            .stamps_ns
            .iter()
            .map(|&n| (n - START_NS) as f64 * 1e-9 + s.offset_at(0.0))
            .collect();
        assert!(on_ref[0] >= -1e-6 && on_ref[0] < period, "{}", on_ref[0]);
        assert!(on_ref
            .windows(2)
            .all(|w| (w[1] - w[0] - period).abs() < 1e-6));
    }

    #[test]
    fn kinds_parse_from_their_names() {
        for k in MissionKind::ALL {
            assert_eq!(k.as_str().parse::<MissionKind>(), Ok(k));
        }
        assert!("nope".parse::<MissionKind>().is_err());
    }
}

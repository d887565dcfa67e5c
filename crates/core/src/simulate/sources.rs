//! Missions of several sources on several clocks, with known truth: one rigid body carrying a
//! reference sensor (a position-only total-station prism) and any number of pose sources (an INS,
//! lidar-inertial odometry, leg odometry, …), each with its own rate, noise, scale error, lever arm and
//! **clock**: shared with the reference, offset, drifting or stepping. This is what an audit of a
//! whole mission must untangle (`trajdrift simulate DIR --grandtour --multi-clock` writes it as
//! GrandTour-like per-sensor bags, see [`super::grandtour::write_multi_clock`]).
//!
//! A source's clock maps true time t (seconds from the start) to its stamps exactly as the
//! single-estimate simulator does ([`SourceClock::stamp_ns`], shared with [`super::simulate`]):
//! stamp = start + t·(1 + ppm·10⁻⁶) − Δt(t), Δt the offset before the step and the step's offset after
//! it. So Δt(t) = offset − ppm·10⁻⁶·t (+ the step): t_source + Δt maps onto the reference clock, the
//! convention of the report and of the shared fixtures' `truth.json`.
//!
//! [`MultiClockConfig::varied`] draws a mission from a seed: every kind of clock once, levers up to
//! 0.5 m (vertical ones included), so tests run many seeds rather than one tuned fixture.

use nalgebra::{UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::simulate::motion::{integrate, state_at, Segment};
use crate::simulate::{topics, white, ClockStep};
use crate::trajectory::Trajectory;

/// A source's clock relative to the reference's (true) clock.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct SourceClock {
    /// Δt at the start, seconds (t_source + Δt = reference clock).
    pub offset_s: f64,
    /// Rate error, ppm; positive when the source's clock runs fast (its Δt falls with time).
    pub drift_ppm: f64,
    /// From true time `at_s` on, Δt is `offset_s` of the step instead.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<ClockStep>,
}

impl SourceClock {
    /// The reference's own clock.
    pub const SHARED: SourceClock = SourceClock {
        offset_s: 0.0,
        drift_ppm: 0.0,
        step: None,
    };

    /// The stamp (ns) this clock gives the true time `t_true_s` (seconds from `start_ns`).
    pub fn stamp_ns(&self, start_ns: i64, t_true_s: f64) -> i64 {
        let t_clock = t_true_s * (1.0 + self.drift_ppm * 1e-6);
        let offset = match self.step {
            Some(s) if t_true_s >= s.at_s => s.offset_s,
            _ => self.offset_s,
        };
        start_ns + ((t_clock - offset) * 1e9).round() as i64
    }

    /// The true Δt at true time `t_true_s`, seconds.
    pub fn offset_at_s(&self, t_true_s: f64) -> f64 {
        let offset = match self.step {
            Some(s) if t_true_s >= s.at_s => s.offset_s,
            _ => self.offset_s,
        };
        offset - self.drift_ppm * 1e-6 * t_true_s
    }

    /// True when it is the reference's clock.
    pub fn is_shared(&self) -> bool {
        *self == SourceClock::SHARED
    }
}

/// What a source publishes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SourceFrame {
    /// Poses in the world (ENU) frame, as an INS publishes them.
    World,
    /// Poses in its own odometry frame, which starts at the identity (lidar, leg odometry).
    Odometry,
}

/// One simulated pose source.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SourceSpec {
    /// Short name (`ins`, `dlio`, …).
    pub name: String,
    pub topic: String,
    pub rate_hz: f64,
    /// White noise on each coordinate, metres.
    pub noise_m: f64,
    /// The source's sensor relative to the reference sensor, body frame (x forward, y left, z up), m.
    pub lever_m: [f64; 3],
    /// Distance scale error (0.01 = 1 % too long); 0 for a world-frame source.
    pub scale_error: f64,
    pub frame: SourceFrame,
    pub clock: SourceClock,
}

/// A mission of a reference and several sources.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MultiClockConfig {
    pub seed: u64,
    /// True time of the first sample, ns since the epoch.
    pub start_time_ns: i64,
    pub ref_rate_hz: f64,
    pub ref_noise_m: f64,
    pub sources: Vec<SourceSpec>,
}

/// A simulated multi-source mission.
#[derive(Debug, Clone)]
pub struct MultiClockMission {
    pub config: MultiClockConfig,
    /// The reference sensor's positions (world ENU), on the true clock.
    pub reference: Trajectory,
    /// Per source (same order as `config.sources`): its poses, on its own clock.
    pub sources: Vec<Trajectory>,
    pub duration_s: f64,
}

/// The clock kinds [`MultiClockConfig::varied`] gives its sources, in order.
pub const VARIED_KINDS: [&str; 4] = ["shared", "offset", "drifting", "stepping"];

impl MultiClockConfig {
    /// A GrandTour-like mission drawn from `seed`: the prism as reference (10 Hz, 2 cm) and four pose
    /// sources, one per clock kind — the INS on the reference's clock, DLIO offset, the state
    /// estimator drifting (40–150 ppm either way), open3d_slam stepping once in the middle third —
    /// each with its own lever (up to 0.5 m, some vertical), rate and noise. `duration_s` sets where
    /// the step falls.
    pub fn varied(seed: u64, duration_s: f64) -> MultiClockConfig {
        let d = Draws::new(seed, duration_s);
        MultiClockConfig {
            seed,
            start_time_ns: 1_718_460_000_000_000_000,
            ref_rate_hz: 10.0,
            ref_noise_m: 0.02,
            sources: vec![
                spec(
                    "ins",
                    topics::INS_TOPIC,
                    50.0,
                    0.005,
                    d.ins_lever,
                    0.0,
                    SourceFrame::World,
                    SourceClock::SHARED,
                ),
                spec(
                    "dlio",
                    topics::DLIO_TOPIC,
                    10.0,
                    0.005,
                    d.dlio_lever,
                    d.dlio_scale,
                    SourceFrame::Odometry,
                    SourceClock {
                        offset_s: d.dlio_offset,
                        ..SourceClock::SHARED
                    },
                ),
                spec(
                    "state_estimator",
                    topics::STATE_ESTIMATOR_TOPIC,
                    50.0,
                    0.003,
                    d.se_lever,
                    d.se_scale,
                    SourceFrame::Odometry,
                    SourceClock {
                        offset_s: d.se_offset,
                        drift_ppm: d.drift,
                        step: None,
                    },
                ),
                spec(
                    "open3d_slam",
                    topics::OPEN3D_SLAM_TOPIC,
                    10.0,
                    0.005,
                    d.o3d_lever,
                    d.o3d_scale,
                    SourceFrame::Odometry,
                    SourceClock {
                        offset_s: d.o3d_offset,
                        drift_ppm: 0.0,
                        step: Some(ClockStep {
                            at_s: d.at_s,
                            offset_s: d.o3d_offset + d.step,
                        }),
                    },
                ),
            ],
        }
    }
}

/// A source's description (a function, so that [`MultiClockConfig::varied`] reads as a table).
#[allow(clippy::too_many_arguments)]
fn spec(
    name: &str,
    topic: &str,
    rate_hz: f64,
    noise_m: f64,
    lever_m: [f64; 3],
    scale_error: f64,
    frame: SourceFrame,
    clock: SourceClock,
) -> SourceSpec {
    SourceSpec {
        name: name.into(),
        topic: topic.into(),
        rate_hz,
        noise_m,
        lever_m,
        scale_error,
        frame,
        clock,
    }
}

/// What [`MultiClockConfig::varied`] draws from its seed, in the order drawn.
struct Draws {
    dlio_offset: f64,
    se_offset: f64,
    drift: f64,
    o3d_offset: f64,
    step: f64,
    at_s: f64,
    ins_lever: [f64; 3],
    dlio_lever: [f64; 3],
    se_lever: [f64; 3],
    o3d_lever: [f64; 3],
    dlio_scale: f64,
    se_scale: f64,
    o3d_scale: f64,
}

impl Draws {
    fn new(seed: u64, duration_s: f64) -> Draws {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6d75_6c74_6963_6c6b);
        let sign = |rng: &mut ChaCha8Rng| if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let lever = |rng: &mut ChaCha8Rng, max: f64| -> [f64; 3] {
            let mut l = [0.0; 3];
            for v in l.iter_mut() {
                *v = (rng.random_range(-max..max) * 100.0_f64).round() / 100.0;
            }
            l
        };
        let offset = |rng: &mut ChaCha8Rng, s: f64| {
            s * (rng.random_range(0.05..0.5_f64) * 1000.0).round() / 1000.0
        };
        let s1 = sign(&mut rng);
        let dlio_offset = offset(&mut rng, s1);
        let s2 = sign(&mut rng);
        let se_offset = offset(&mut rng, s2);
        let s3 = sign(&mut rng);
        let drift = s3 * rng.random_range(40.0..150.0_f64).round();
        let s4 = sign(&mut rng);
        let o3d_offset = offset(&mut rng, s4);
        let s5 = sign(&mut rng);
        let step = s5 * (rng.random_range(0.2..0.6) * 1000.0_f64).round() / 1000.0;
        let at_s = (rng.random_range(0.35..0.65) * duration_s).round();
        let ins_lever = lever(&mut rng, 0.3);
        let dlio_lever = lever(&mut rng, 0.5);
        let se_lever = lever(&mut rng, 0.3);
        let o3d_lever = lever(&mut rng, 0.5);
        let scale =
            |rng: &mut ChaCha8Rng| (rng.random_range(-0.02..0.02) * 1000.0_f64).round() / 1000.0;
        let (dlio_scale, se_scale, o3d_scale) = (scale(&mut rng), scale(&mut rng), scale(&mut rng));
        Draws {
            dlio_offset,
            se_offset,
            drift,
            o3d_offset,
            step,
            at_s,
            ins_lever,
            dlio_lever,
            se_lever,
            o3d_lever,
            dlio_scale,
            se_scale,
            o3d_scale,
        }
    }
}

/// Simulates `config` on `route` (the body's motion of [`super::simulate`]).
pub fn simulate_sources(config: &MultiClockConfig, route: &[Segment]) -> MultiClockMission {
    const RATE: f64 = 1000.0;
    let states = integrate(route, RATE, 0.4, 1.0);
    let duration_s = states.last().map_or(0.0, |s| s.t);
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    let sensor = |t: f64, l: &Vector3<f64>| {
        let s = state_at(&states, RATE, t);
        let r = UnitQuaternion::from_euler_angles(0.0, 0.0, s.yaw);
        (s.position + r * l, r)
    };
    let mut reference = Trajectory::new(false);
    let n_ref = (duration_s * config.ref_rate_hz).floor() as usize + 1;
    for i in 0..n_ref {
        let t = i as f64 / config.ref_rate_hz;
        let (p, _) = sensor(t, &Vector3::zeros());
        let noise = white(&mut rng, config.ref_noise_m);
        reference.push(
            config.start_time_ns + (t * 1e9).round() as i64,
            p + noise,
            None,
        );
    }
    let sources = config
        .sources
        .iter()
        .map(|s| {
            let lever = Vector3::from(s.lever_m);
            let (p0, r0) = sensor(0.0, &lever);
            let mut out = Trajectory::new(true);
            let n = (duration_s * s.rate_hz).floor() as usize + 1;
            for i in 0..n {
                let t = i as f64 / s.rate_hz;
                let (p, r) = sensor(t, &lever);
                let (p, q) = match s.frame {
                    SourceFrame::World => (p, r),
                    SourceFrame::Odometry => (
                        r0.inverse() * (p - p0) * (1.0 + s.scale_error),
                        r0.inverse() * r,
                    ),
                };
                let noise = white(&mut rng, s.noise_m);
                let stamp = s.clock.stamp_ns(config.start_time_ns, t);
                // A backward step repeats a stretch of stamps; a recorder keeps them increasing.
                if out.stamps_ns.last().is_some_and(|&last| stamp <= last) {
                    continue;
                }
                out.push(stamp, p + noise, Some(q));
            }
            out
        })
        .collect();
    MultiClockMission {
        config: config.clone(),
        reference,
        sources,
        duration_s,
    }
}

/// The truth as JSON, in the shape of the shared `multi_clock` fixture's `truth.json`: the reference
/// topic and, per source, its topic, Δt at the start, drift (ppm, > 0 fast), step (true seconds from
/// the start, and the change of Δt), lever (relative to the reference sensor, body frame) and whether
/// it shares the reference's clock.
pub fn multi_clock_truth(m: &MultiClockMission, reference_topic: &str) -> serde_json::Value {
    let mut sources = serde_json::Map::new();
    for s in &m.config.sources {
        let c = &s.clock;
        sources.insert(
            s.name.clone(),
            serde_json::json!({
                "topic": s.topic,
                "offset_at_start_s": c.offset_s,
                "drift_ppm": c.drift_ppm,
                "step_at_s": c.step.map(|x| x.at_s),
                "step_s": c.step.map(|x| x.offset_s - c.offset_s),
                "lever_m": s.lever_m,
                "scale_error": s.scale_error,
                "rate_hz": s.rate_hz,
                "shares_reference_clock": c.is_shared(),
            }),
        );
    }
    serde_json::json!({
        "generator": concat!("trajdrift simulate --grandtour --multi-clock ", env!("CARGO_PKG_VERSION")),
        "reference": reference_topic,
        "seed": m.config.seed,
        "duration_s": m.duration_s,
        "profile": "ground",
        "start_time_s": m.config.start_time_ns as f64 * 1e-9,
        "convention": "t_source + dt maps source stamps onto the reference clock; dt(t) = offset_at_start_s - drift_ppm 1e-6 t (+ step_s from step_at_s on), t true seconds from the start",
        "sources": sources,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_follow_the_clock_model() {
        let c = SourceClock {
            offset_s: 0.2,
            drift_ppm: 100.0,
            step: Some(ClockStep {
                at_s: 100.0,
                offset_s: -0.3,
            }),
        };
        // Before the step: stamp + Δt(t) = true time.
        let t = 50.0;
        let stamp = c.stamp_ns(0, t) as f64 * 1e-9;
        assert!((stamp + c.offset_at_s(t) - t).abs() < 1e-6);
        let t = 150.0;
        let stamp = c.stamp_ns(0, t) as f64 * 1e-9;
        assert!((stamp + c.offset_at_s(t) - t).abs() < 1e-6);
        assert!(SourceClock::SHARED.is_shared());
    }

    #[test]
    fn varied_missions_hold_every_clock_kind() {
        for seed in 0..20 {
            let c = MultiClockConfig::varied(seed, 1200.0);
            let s = &c.sources;
            assert!(s[0].clock.is_shared());
            assert!(s[1].clock.offset_s.abs() >= 0.05 && s[1].clock.drift_ppm == 0.0);
            assert!((40.0..=150.0).contains(&s[2].clock.drift_ppm.abs()));
            let step = s[3].clock.step.unwrap();
            assert!((step.offset_s - s[3].clock.offset_s).abs() >= 0.2);
            assert!(step.at_s > 0.3 * 1200.0 && step.at_s < 0.7 * 1200.0);
        }
    }
}

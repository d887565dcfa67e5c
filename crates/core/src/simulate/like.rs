//! Missions shaped like a user's recording: the accuracy to expect on *that* recording.
//!
//! The calibration table of [`crate::simulate::scenario`] says how the time alignment does on
//! missions of every kind; a user wants to know how it does on theirs. [`shape_of`] reads what a
//! recording's two trajectories say about themselves — the reference's path (its speed and its turns,
//! second by second), both rates, both noise levels, the reference's outages, and whether the robot
//! walks — and [`scenario_like`] draws a validation mission with that shape: the same route (driven by
//! the simulator's body, so speed and curvature follow the user's within the body's acceleration
//! limits), the same rates, noise and outages, and a known clock offset injected. What the recording
//! cannot say is drawn as for any mission from the seed: the estimate's lever arm, its scale error and
//! heading drift, the gait, the terrain. The missions are then evaluated with every default and graded
//! against the injected truth like any other.
//!
//! How each figure is read:
//!
//! - **route**: the reference is smoothed over legs of [`LEG_S`] seconds (the mean position of the
//!   samples within half a leg of each boundary, linear interpolation where there are none); a leg's
//!   speed is its chord over its duration, its curvature the change of heading to the next leg over the
//!   distance. Below [`STAND_MPS`] the robot stands; if the estimate has orientations, the yaw it turns
//!   while standing becomes a turn in place.
//! - **noise**: white noise per coordinate from the second differences of the samples at their own
//!   rate (σ² = Var(Δ²p)/6 for white noise), robustly (the median absolute deviation), so motion at a
//!   high rate barely enters.
//! - **outages**: reference gaps longer than [`OUTAGE_PERIODS`] sample periods (and at least 1 s).
//! - **legged or wheeled**: a robot whose median moving speed is below [`LEGGED_BELOW_MPS`] is
//!   simulated with a gait (the walking speeds of legged robots are 0.25–0.5 m/s, wheeled field robots
//!   drive at 0.8 m/s and more); a choice, stated in the output.
//!
//! The estimate's own trajectory enters through its rate, its noise and its turns in place only: its
//! drift and frame are the simulator's, since the truth must be known.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::simulate::scenario::{Leg, MissionKind, Scenario};
use crate::stats::median;
use crate::trajectory::Trajectory;

/// Length of a leg of the route, seconds.
pub const LEG_S: f64 = 1.0;
/// Slower than this, the robot stands (m/s).
pub const STAND_MPS: f64 = 0.05;
/// A reference gap longer than this many sample periods is an outage.
pub const OUTAGE_PERIODS: f64 = 5.0;
/// A median moving speed below this is simulated as a legged robot, m/s.
pub const LEGGED_BELOW_MPS: f64 = 0.7;

/// What a recording says about its own shape.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Shape {
    /// The reference's span, seconds.
    pub duration_s: f64,
    /// Median sample rates, Hz.
    pub ref_rate_hz: f64,
    pub est_rate_hz: f64,
    /// White noise per coordinate, metres.
    pub ref_noise_m: f64,
    pub est_noise_m: f64,
    /// The route, legs of [`LEG_S`] seconds.
    pub route: Vec<Leg>,
    /// Reference outages, seconds from its start.
    pub outages: Vec<(f64, f64)>,
    /// Median speed while moving, m/s.
    pub moving_speed_mps: f64,
    /// Simulated with a gait (see the module doc).
    pub legged: bool,
}

/// Median sample rate of stamps `t` (seconds), Hz.
fn rate_hz(t: &[f64]) -> f64 {
    let periods: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    median(&periods).map_or(f64::NAN, |p| 1.0 / p)
}

/// White noise per coordinate from second differences (robust: 1.4826·MAD/√6), metres.
fn white_noise_m(p: &[nalgebra::Vector3<f64>]) -> f64 {
    let second: Vec<f64> = p
        .windows(3)
        .flat_map(|w| {
            let d = w[2] - 2.0 * w[1] + w[0];
            [d.x, d.y, d.z]
        })
        .collect();
    let Some(m) = median(&second) else {
        return f64::NAN;
    };
    let deviations: Vec<f64> = second.iter().map(|x| (x - m).abs()).collect();
    median(&deviations).map_or(f64::NAN, |mad| 1.4826 * mad / 6f64.sqrt())
}

/// The mean horizontal position of the samples within `half_s` of `t` (linear interpolation of the
/// neighbours when none is that close).
fn smoothed_at(t: &[f64], p: &[nalgebra::Vector3<f64>], at: f64, half_s: f64) -> [f64; 2] {
    let (lo, hi) = (
        t.partition_point(|&x| x < at - half_s),
        t.partition_point(|&x| x <= at + half_s),
    );
    if hi > lo {
        let n = (hi - lo) as f64;
        let (sx, sy) = p[lo..hi]
            .iter()
            .fold((0.0, 0.0), |(a, b), q| (a + q.x, b + q.y));
        return [sx / n, sy / n];
    }
    let j = t.partition_point(|&x| x < at).clamp(1, t.len() - 1);
    let f = ((at - t[j - 1]) / (t[j] - t[j - 1])).clamp(0.0, 1.0);
    let q = p[j - 1] + (p[j] - p[j - 1]) * f;
    [q.x, q.y]
}

/// The estimate's yaw turned between `a` and `b` (seconds from the reference's first stamp), radians.
fn yaw_turned(t: &[f64], q: &[nalgebra::UnitQuaternion<f64>], a: f64, b: f64) -> f64 {
    let at = |x: f64| {
        let j = t.partition_point(|&s| s < x).min(t.len() - 1);
        q[j].euler_angles().2
    };
    wrap(at(b) - at(a))
}

/// An angle in (−π, π].
fn wrap(a: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    a - tau * ((a + std::f64::consts::PI) / tau).floor()
}

/// The route: legs of [`LEG_S`] seconds over the smoothed reference (see the module doc).
fn route_of(
    t: &[f64],
    p: &[nalgebra::Vector3<f64>],
    estimate: Option<(&[f64], &[nalgebra::UnitQuaternion<f64>])>,
) -> Vec<Leg> {
    let duration = t[t.len() - 1] - t[0];
    let n = (duration / LEG_S).floor() as usize;
    let points: Vec<[f64; 2]> = (0..=n)
        .map(|k| smoothed_at(t, p, t[0] + k as f64 * LEG_S, 0.5 * LEG_S))
        .collect();
    let chord = |k: usize| {
        let (a, b) = (points[k], points[k + 1]);
        (b[0] - a[0], b[1] - a[1])
    };
    (0..n)
        .map(|k| {
            let (dx, dy) = chord(k);
            let speed = dx.hypot(dy) / LEG_S;
            let mut leg = Leg {
                duration_s: LEG_S,
                speed_mps: 0.0,
                curvature: 0.0,
                spin_rps: 0.0,
            };
            if speed >= STAND_MPS {
                leg.speed_mps = speed;
                if k + 1 < n {
                    let (ex, ey) = chord(k + 1);
                    if ex.hypot(ey) / LEG_S >= STAND_MPS {
                        leg.curvature = wrap(ey.atan2(ex) - dy.atan2(dx)) / (speed * LEG_S);
                    }
                }
            } else if let Some((et, eq)) = estimate {
                let a = k as f64 * LEG_S;
                leg.spin_rps = yaw_turned(et, eq, a, a + LEG_S) / LEG_S;
            }
            leg
        })
        .collect()
}

/// Reference gaps longer than [`OUTAGE_PERIODS`] periods and 1 s, seconds from its start.
fn outages_of(t: &[f64], rate_hz: f64) -> Vec<(f64, f64)> {
    let min_gap = (OUTAGE_PERIODS / rate_hz).max(1.0);
    t.windows(2)
        .filter(|w| w[1] - w[0] > min_gap)
        .map(|w| (w[0] - t[0], w[1] - t[0]))
        .collect()
}

/// The shape of a recording's reference and estimate (stamps as recorded, each on its own clock);
/// `None` when either has fewer than 10 samples or the reference spans less than 30 s.
pub fn shape_of(reference: &Trajectory, estimate: &Trajectory) -> Option<Shape> {
    if reference.len() < 10 || estimate.len() < 10 {
        return None;
    }
    // Both from the reference's first stamp: the estimate's turns in place are looked up at the
    // reference's times (their clocks differ by the offset, a second or less, not by their starts).
    let rt = reference.times_s(reference.stamps_ns[0]);
    let et = estimate.times_s(reference.stamps_ns[0]);
    let duration_s = rt[rt.len() - 1];
    if duration_s < 30.0 {
        return None;
    }
    let ref_rate_hz = rate_hz(&rt);
    let est_rate_hz = rate_hz(&et);
    let route = route_of(
        &rt,
        &reference.positions,
        estimate.orientations.as_deref().map(|q| (et.as_slice(), q)),
    );
    let moving: Vec<f64> = route
        .iter()
        .filter(|l| l.speed_mps > 0.0)
        .map(|l| l.speed_mps)
        .collect();
    let moving_speed_mps = median(&moving).unwrap_or(f64::NAN);
    Some(Shape {
        duration_s,
        ref_rate_hz,
        est_rate_hz,
        ref_noise_m: white_noise_m(&reference.positions),
        est_noise_m: white_noise_m(&estimate.positions),
        outages: outages_of(&rt, ref_rate_hz),
        legged: moving_speed_mps < LEGGED_BELOW_MPS,
        moving_speed_mps,
        route,
    })
}

/// A validation mission of `shape` drawn from `seed`: the route, rates, noise and outages of the
/// shape; the clock a constant offset of −2…2 s; the rest drawn as for a ground or legged mission.
pub fn scenario_like(shape: &Shape, seed: u64) -> Scenario {
    let kind = if shape.legged {
        MissionKind::Legged
    } else {
        MissionKind::Ground
    };
    let mut s = Scenario::draw(kind, seed);
    if !shape.legged {
        // A ground mission is drawn legged now and then: this one is wheeled.
        s.legged = false;
        s.gait = None;
    }
    // Its own stream for the offset: the drawn mission's draws stay those of the kind's.
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x4c49_4b45);
    s.route = shape.route.clone();
    s.ref_rate_hz = shape.ref_rate_hz;
    s.est_rate_hz = shape.est_rate_hz;
    s.ref_noise_m = shape.ref_noise_m;
    s.est_noise_m = shape.est_noise_m;
    s.outages = shape.outages.clone();
    s.jumps.clear();
    s.receipt_latency_s = None;
    s.clock_drift_ppm = 0.0;
    s.clock_step = None;
    s.time_offset_s = -2.0 + 4.0 * rng.random::<f64>();
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::scenario::START_NS;

    #[test]
    fn a_simulated_mission_s_shape_is_read_back() {
        let s = Scenario::draw(MissionKind::Ground, 7);
        let m = s.simulate();
        let shape = shape_of(&m.reference, &m.estimate).expect("a shape");
        assert!((shape.ref_rate_hz - s.ref_rate_hz).abs() < 0.01 * s.ref_rate_hz);
        assert!((shape.est_rate_hz - s.est_rate_hz).abs() < 0.01 * s.est_rate_hz);
        assert!((shape.duration_s - m.duration_s).abs() < 2.0 / s.ref_rate_hz + 1.0);
        // The route's mean speed within 10 % of the simulated one.
        let mean = |r: &[Leg]| {
            r.iter().map(|l| l.speed_mps * l.duration_s).sum::<f64>()
                / r.iter().map(|l| l.duration_s).sum::<f64>()
        };
        let (got, want) = (mean(&shape.route), mean(&s.route));
        assert!((got - want).abs() < 0.1 * want, "{got} vs {want}");
        assert_eq!(shape.legged, s.legged);
        let like = scenario_like(&shape, 3);
        assert_eq!(like.ref_rate_hz, shape.ref_rate_hz);
        assert!(like.clock_step.is_none() && like.clock_drift_ppm == 0.0);
        let again = like.simulate();
        assert!(again.reference.stamps_ns[0] >= START_NS);
    }

    #[test]
    fn white_noise_is_read_from_second_differences() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let p: Vec<nalgebra::Vector3<f64>> = (0..20_000)
            .map(|i| {
                let n =
                    |rng: &mut ChaCha8Rng| rng.sample::<f64, _>(rand_distr::StandardNormal) * 0.01;
                nalgebra::Vector3::new(0.1 * i as f64 + n(&mut rng), n(&mut rng), n(&mut rng))
            })
            .collect();
        let s = white_noise_m(&p);
        assert!((s - 0.01).abs() < 0.0005, "{s}");
    }
}

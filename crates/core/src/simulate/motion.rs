//! The body's motion for simulated missions: a planar path of stops, straights and arcs driven with
//! bounded acceleration, integrated at 1 kHz. Smooth speed and curvature keep the path physically
//! plausible, so curvature and speed signatures look like a real robot's.

use nalgebra::Vector3;

/// One leg of the mission.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// How long the leg lasts, seconds.
    pub duration_s: f64,
    /// Target forward speed, m/s (0 = stop).
    pub speed_mps: f64,
    /// Target path curvature, 1/m (positive = left turn).
    pub curvature: f64,
}

/// The body's state at one instant of the dense integration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyState {
    /// Time since the start, seconds.
    pub t: f64,
    /// Position in the world frame (ENU), metres.
    pub position: Vector3<f64>,
    /// Heading (yaw about +z), radians.
    pub yaw: f64,
}

/// Integrates `segments` at `rate_hz`, starting at the origin with heading `yaw0`. Speed follows each
/// segment's target with at most `accel` m/s²; curvature follows with at most 0.5 (1/m)/s.
pub fn integrate(segments: &[Segment], rate_hz: f64, yaw0: f64, accel: f64) -> Vec<BodyState> {
    let dt = 1.0 / rate_hz;
    let total: f64 = segments.iter().map(|s| s.duration_s).sum();
    let n = (total * rate_hz).round() as usize + 1;
    let mut out = Vec::with_capacity(n);
    let (mut p, mut yaw, mut v, mut k) = (Vector3::zeros(), yaw0, 0.0_f64, 0.0_f64);
    let mut seg_end = 0.0;
    let mut seg_iter = segments.iter();
    let mut seg = Segment {
        duration_s: 0.0,
        speed_mps: 0.0,
        curvature: 0.0,
    };
    for i in 0..n {
        let t = i as f64 * dt;
        while t >= seg_end - 1e-12 {
            match seg_iter.next() {
                Some(s) => {
                    seg = *s;
                    seg_end += s.duration_s;
                }
                None => {
                    seg.speed_mps = 0.0;
                    seg_end = f64::INFINITY;
                }
            }
        }
        out.push(BodyState {
            t,
            position: p,
            yaw,
        });
        v += (seg.speed_mps - v).clamp(-accel * dt, accel * dt);
        k += (seg.curvature - k).clamp(-0.5 * dt, 0.5 * dt);
        yaw += v * k * dt;
        p += Vector3::new(yaw.cos(), yaw.sin(), 0.0) * (v * dt);
    }
    out
}

/// Linear interpolation of the dense states at time `t` (clamped to the span).
pub fn state_at(states: &[BodyState], rate_hz: f64, t: f64) -> BodyState {
    let x = (t * rate_hz).clamp(0.0, (states.len() - 1) as f64);
    let i = (x.floor() as usize).min(states.len().saturating_sub(2));
    let f = x - i as f64;
    let (a, b) = (&states[i], &states[(i + 1).min(states.len() - 1)]);
    BodyState {
        t,
        position: a.position + (b.position - a.position) * f,
        yaw: a.yaw + (b.yaw - a.yaw) * f,
    }
}

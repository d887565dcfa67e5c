//! The signals the offset search correlates, one per trajectory and method: the curvature signature
//! of eq. (1), unsigned and signed ([`crate::align::curvature`]), and the windowed speed with its
//! heading rate ([`crate::align::speed`]). [`Pair`] computes each at most once per evaluation and
//! shares it between the methods, the `auto` re-run without stands and the offset profile: on a
//! 2-hour 200 Hz mission a signal is tens of megabytes and a signature a third of a second.

use std::sync::{Arc, OnceLock};

use nalgebra::Vector3;

use crate::align::curvature::curvature_signature_each;
use crate::align::offset_params::{OffsetMethod, OffsetParams};
use crate::align::speed::speed_profile_each;
use crate::error::{Error, Result};

/// One trajectory's signal for a method: times, values and (speed only) heading rates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Signal {
    /// Sample times, seconds; shared by the unsigned and the signed curvature (one signature).
    pub t: Arc<Vec<f64>>,
    /// Values: curvature (1/m), signed curvature or speed (m/s).
    pub v: Vec<f64>,
    /// Heading rates, rad/s (speed only; empty otherwise).
    pub yaw_rate: Vec<f64>,
}

/// A signal's times and values as the offset profile and the clock model read them: the estimate's
/// speed is corrected for a lateral lever arm d (v + d·ω) where it is read, so no corrected copy of
/// the whole signal is made.
#[derive(Debug, Clone, Copy)]
pub struct SignalView<'a> {
    /// Sample times, seconds.
    pub t: &'a [f64],
    v: &'a [f64],
    yaw_rate: &'a [f64],
    lever_m: Option<f64>,
}

impl<'a> SignalView<'a> {
    /// The signal as it is.
    pub fn of(s: &'a Signal) -> Self {
        SignalView {
            t: &s.t,
            v: &s.v,
            yaw_rate: &s.yaw_rate,
            lever_m: None,
        }
    }

    /// The speed signal `s` with a lateral lever arm of `lever_m` metres taken out.
    pub fn with_lever(s: &'a Signal, lever_m: f64) -> Self {
        SignalView {
            lever_m: Some(lever_m),
            ..Self::of(s)
        }
    }

    /// Value `i`.
    pub fn value(&self, i: usize) -> f64 {
        match self.lever_m {
            Some(d) => self.v[i] + d * self.yaw_rate[i],
            None => self.v[i],
        }
    }

    /// The values of `range`, borrowed when nothing is corrected.
    pub fn values(&self, range: std::ops::Range<usize>) -> std::borrow::Cow<'a, [f64]> {
        match self.lever_m {
            Some(_) => range.map(|i| self.value(i)).collect(),
            None => std::borrow::Cow::Borrowed(&self.v[range]),
        }
    }
}

/// The reference's and the estimate's signal, shared.
pub type SignalPair = (Arc<Signal>, Arc<Signal>);

/// Time intervals `[a, b]`, seconds.
pub type Intervals<'a> = &'a [(f64, f64)];

/// The windowed speed and heading rate of one trajectory (see [`crate::align::speed`]).
fn speed_signal(t: &[f64], p: &[Vector3<f64>], params: &OffsetParams) -> Signal {
    let gap = params.max_gap_s.unwrap_or(params.curvature.dt_max_s);
    let noise = isotropic_noise(t, p).unwrap_or(0.0);
    // At most one value a sample: reserved once (no doubling, no slack).
    let n = t.len();
    let (mut times, mut v, mut yaw_rate) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    speed_profile_each(t, p, params.speed_window_s, gap, noise, |s| {
        times.push(s.t);
        v.push(s.speed);
        yaw_rate.push(s.yaw_rate);
    });
    times.shrink_to_fit();
    v.shrink_to_fit();
    yaw_rate.shrink_to_fit();
    Signal {
        t: Arc::new(times),
        v,
        yaw_rate,
    }
}

/// The two trajectories of one evaluation (times from a common origin, the estimate's on its own
/// clock) and their signals, each computed at most once: by the first method that needs it, then
/// shared with the other methods, the `auto` re-run without stands and the offset profile.
pub struct Pair<'a> {
    pub reference: (&'a [f64], &'a [Vector3<f64>]),
    pub estimate: (&'a [f64], &'a [Vector3<f64>]),
    cache: &'a SignalCache,
}

/// The signals of a [`Pair`] once computed (unsigned and signed curvature come from one signature),
/// reference first.
#[derive(Default)]
pub struct SignalCache {
    curvature: [OnceLock<SignalPair>; 2],
    speed: [OnceLock<Arc<Signal>>; 2],
}

impl<'a> Pair<'a> {
    pub fn new(
        reference: (&'a [f64], &'a [Vector3<f64>]),
        estimate: (&'a [f64], &'a [Vector3<f64>]),
        cache: &'a SignalCache,
    ) -> Pair<'a> {
        Pair {
            reference,
            estimate,
            cache,
        }
    }

    /// The reference's and the estimate's signal for `method` (the curvature parameters, speed
    /// window and gap must be those of every call with this cache).
    pub fn signals(&self, method: OffsetMethod, params: &OffsetParams) -> Result<SignalPair> {
        let (r, e) = (self.one(0, method, params), self.one(1, method, params));
        checked(&r, method, "reference")?;
        checked(&e, method, "estimate")?;
        Ok((r, e))
    }

    fn one(&self, k: usize, method: OffsetMethod, params: &OffsetParams) -> Arc<Signal> {
        let (t, p) = if k == 0 {
            self.reference
        } else {
            self.estimate
        };
        if method == OffsetMethod::Speed {
            return self.cache.speed[k]
                .get_or_init(|| Arc::new(speed_signal(t, p, params)))
                .clone();
        }
        let (unsigned, signed) = self.cache.curvature[k].get_or_init(|| {
            // At most one value a sample: reserved once (no doubling, no slack).
            let n = t.len();
            let (mut tu, mut u, mut sv) = (
                Vec::with_capacity(n),
                Vec::with_capacity(n),
                Vec::with_capacity(n),
            );
            curvature_signature_each(t, p, &params.curvature, |c| {
                tu.push(c.t);
                u.push(c.curvature);
                sv.push(c.signed_curvature());
            });
            tu.shrink_to_fit();
            u.shrink_to_fit();
            sv.shrink_to_fit();
            let t = Arc::new(tu);
            let signal = |v| {
                Arc::new(Signal {
                    t: t.clone(),
                    v,
                    yaw_rate: Vec::new(),
                })
            };
            (signal(u), signal(sv))
        });
        if method == OffsetMethod::Curvature {
            unsigned.clone()
        } else {
            signed.clone()
        }
    }
}

/// `s` when it holds at least 3 samples.
fn checked(s: &Signal, method: OffsetMethod, what: &str) -> Result<()> {
    if s.t.len() < 3 {
        return Err(Error::TooFewSamples {
            what: format!("{what} {} signal", method.as_str()),
            n: s.t.len(),
            need: 3,
        });
    }
    Ok(())
}

/// σ of white position noise per coordinate from the norms of the third differences of evenly spaced
/// samples (|Δ³p| of isotropic noise is σ·√20 times a χ with 3 degrees of freedom, median 1.538):
/// unlike a per-axis estimate it is the same in every rotated frame, so the speed signal and its
/// heading rate are too.
fn isotropic_noise(t: &[f64], p: &[Vector3<f64>]) -> Option<f64> {
    let n = t.len().min(p.len());
    if n < 40 {
        return None;
    }
    let typical = crate::stats::median_step(&t[..n])?;
    if typical.is_nan() || typical <= 0.0 {
        return None;
    }
    let even = |dt: f64| (dt - typical).abs() <= 0.2 * typical;
    let mut d3: Vec<f64> = (3..n)
        .filter(|&i| (i - 2..=i).all(|k| even(t[k] - t[k - 1])))
        .map(|i| (p[i] - 3.0 * p[i - 1] + 3.0 * p[i - 2] - p[i - 3]).norm())
        .filter(|v| v.is_finite())
        .collect();
    if d3.len() < 30 {
        return None;
    }
    let mid = d3.len() / 2;
    Some(*d3.select_nth_unstable_by(mid, f64::total_cmp).1 / (20f64.sqrt() * 1.538))
}

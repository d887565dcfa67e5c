//! The pose fit's tests, on simulated missions with a known offset and lever: the offset and lever
//! recovered, jumps of the estimate, the σ against the spread of the answers, a clock step located,
//! the profile's calibration by the windows' scatter.

use super::shared::{lever_weight, SharedFit};
use super::*;

/// A simulated mission: the reference 10 Hz over 110 s, the estimate at 20 Hz stamped on its own
/// clock (`dt_at(t)` late, t true time), its sensor `lever` from the reference point, in a
/// rotated frame with a 2 % scale error; the body drives curves at `speed(t)`.
#[derive(Clone)]
struct Sim {
    ref_t: Vec<f64>,
    ref_p: Vec<Vector3<f64>>,
    t: Vec<f64>,
    p: Vec<Vector3<f64>>,
    q: Vec<UnitQuaternion<f64>>,
    jumps: Vec<(f64, f64)>,
}

impl Sim {
    fn new(dt_at: &dyn Fn(f64) -> f64, speed: &dyn Fn(f64) -> f64, lever: Vector3<f64>) -> Sim {
        Sim::from(dt_at, speed, lever, 1.0)
    }

    /// [`Sim::new`] with the reference's first sample at `ref_start_s` (true time).
    fn from(
        dt_at: &dyn Fn(f64) -> f64,
        speed: &dyn Fn(f64) -> f64,
        lever: Vector3<f64>,
        ref_start_s: f64,
    ) -> Sim {
        let yaw_at = |t: f64| 0.8 * (0.05 * t).sin() + 0.3 * (0.13 * t).cos();
        // Integrate the body at 1 kHz.
        let n = 120_000;
        let mut pos = Vec::with_capacity(n);
        let mut yaws = Vec::with_capacity(n);
        let mut p = Vector3::zeros();
        for i in 0..n {
            let t = i as f64 * 0.001;
            let yaw = yaw_at(t);
            pos.push(p);
            yaws.push(yaw);
            p += Vector3::new(yaw.cos(), yaw.sin(), 0.0) * speed(t) * 0.001;
        }
        let at = |t: f64| {
            let i = ((t * 1000.0) as usize).min(n - 1);
            (pos[i], yaws[i])
        };
        let ref_t: Vec<f64> = (0..1100).map(|i| ref_start_s + i as f64 * 0.1).collect();
        let ref_p: Vec<Vector3<f64>> = ref_t.iter().map(|&t| at(t).0).collect();
        let frame = UnitQuaternion::from_euler_angles(0.0, 0.0, 1.1);
        let (mut et, mut ep, mut eq) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..2300 {
            let t_true = 0.5 + i as f64 * 0.05;
            let (p, yaw) = at(t_true);
            let r = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
            et.push(t_true - dt_at(t_true));
            ep.push(frame * ((p + r * lever) * 1.02) + Vector3::new(5.0, -3.0, 1.0));
            eq.push(frame * r);
        }
        let jumps = crate::align::jumps::jumps(&et, &ep, 1.0);
        Sim {
            ref_t,
            ref_p,
            t: et,
            p: ep,
            q: eq,
            jumps,
        }
    }

    /// White noise of `sd_m` on each coordinate of the reference, drawn from `rng`.
    fn reference_noise(mut self, rng: &mut rand_chacha::ChaCha8Rng, sd_m: f64) -> Sim {
        use rand_distr::{Distribution, Normal};
        let noise = Normal::new(0.0, sd_m).unwrap();
        for p in &mut self.ref_p {
            *p += Vector3::from_fn(|_, _| noise.sample(rng));
        }
        self
    }

    /// The estimate stamped at receipt: each stamp late by a draw of `latency`, the samples
    /// re-ordered by stamp.
    fn stamped_at_receipt(
        mut self,
        rng: &mut rand_chacha::ChaCha8Rng,
        latency: &impl rand_distr::Distribution<f64>,
    ) -> Sim {
        let mut samples: Vec<(f64, Vector3<f64>, UnitQuaternion<f64>)> = (0..self.t.len())
            .map(|i| (self.t[i] + latency.sample(rng), self.p[i], self.q[i]))
            .collect();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.t = samples.iter().map(|s| s.0).collect();
        self.p = samples.iter().map(|s| s.1).collect();
        self.q = samples.iter().map(|s| s.2).collect();
        self.jumps = crate::align::jumps::jumps(&self.t, &self.p, 1.0);
        self
    }

    /// The estimate moved by `by` from `at_s` on (its clock): a localiser correcting itself.
    fn jumped(mut self, at_s: f64, by: Vector3<f64>) -> Sim {
        for (t, p) in self.t.iter().zip(&mut self.p) {
            if *t >= at_s {
                *p += by;
            }
        }
        self.jumps = crate::align::jumps::jumps(&self.t, &self.p, 1.0);
        self
    }

    /// The body bobbing `amp_m` up and down at `hz` (a walking robot's gait), seen by both
    /// sensors; `dt_s` the estimate's constant offset (its stamps are true time less it).
    fn bobbing(mut self, amp_m: f64, hz: f64, dt_s: f64) -> Sim {
        let bob = |t: f64| Vector3::z() * amp_m * (std::f64::consts::TAU * hz * t).sin();
        for (t, p) in self.ref_t.iter().zip(&mut self.ref_p) {
            *p += bob(*t);
        }
        // The estimate's frame turns about z only and scales by 1.02 (see `new`).
        for (t, p) in self.t.iter().zip(&mut self.p) {
            *p += bob(*t + dt_s) * 1.02;
        }
        self
    }

    /// Every `k`-th sample of the estimate kept (a slower estimate of the same motion).
    fn thinned(mut self, k: usize) -> Sim {
        fn keep<T>(v: &mut Vec<T>, k: usize) {
            let all = std::mem::take(v);
            *v = all.into_iter().step_by(k).collect();
        }
        keep(&mut self.t, k);
        keep(&mut self.p, k);
        keep(&mut self.q, k);
        self
    }

    /// Every `k`-th reference sample kept (10 Hz to 2 Hz with `k` = 5).
    fn reference_thinned(mut self, k: usize) -> Sim {
        self.ref_t = self.ref_t.iter().copied().step_by(k).collect();
        self.ref_p = self.ref_p.iter().copied().step_by(k).collect();
        self
    }

    fn data(&self) -> PoseData<'_> {
        PoseData {
            ref_t: &self.ref_t,
            ref_p: &self.ref_p,
            estimate: PoseTrack {
                t: &self.t,
                p: &self.p,
                q: &self.q,
                jumps: &self.jumps,
            },
            params: PoseFitParams::new(1.0),
        }
    }
}

/// One offset and the lever over the windows `w`, from `start_s` and no lever.
fn constant_from(data: &PoseData<'_>, w: &[Window], start_s: f64) -> PoseFit {
    let shape = ClockShape::Constant;
    fit(data, w, shape, vec![start_s], Vector3::zeros(), true).unwrap()
}

/// A body driving curves with speed changes; the estimate 0.3 m ahead and 0.2 m above its
/// reference point, in a rotated frame with a 2 % scale error and a known offset: the fit
/// recovers the offset to well under a millisecond and the horizontal lever to a centimetre.
#[test]
fn recovers_offset_and_lever_on_a_noise_free_mission() {
    let dt_true = 0.137;
    let lever = Vector3::new(0.3, 0.0, 0.2);
    let sim = Sim::new(&|_| dt_true, &|t| 1.0 + 0.5 * (0.21 * t).sin(), lever);
    let data = sim.data();
    let w = data.windows();
    let f = constant_from(&data, &w, 0.1);
    assert!((f.theta[0] - dt_true).abs() < 5e-4, "{:?}", f.theta);
    // The horizontal lever, scaled like the estimate; the vertical one is invisible without tilt
    // (the prior keeps it at 0).
    let want = Vector3::new(lever.x, lever.y, 0.0) * 1.02;
    assert!((f.lever_m - want).norm() < 0.01, "{:?}", f.lever_m);
    assert!(f.converged);
}

/// A walking robot at 0.3–0.5 m/s whose body bobs 1.5 cm at 4.5 Hz (twice a trot), seen by a 20 Hz
/// estimate: with the Newton Jacobian's difference two periods wider than the instrument's (the
/// default, ±150 ms, whose response to 3.3–6.7 Hz is negative) J = Σ v·w is negative in the
/// windows at the true offset and lever — a shift in time along a steady walk is mostly a
/// translation, which each window's similarity takes up, so the bob decides J's sign — and Newton
/// steps away from the truth (here into a basin 0.43 s off, which the clock model rejects as
/// another basin); one period wider ([`NARROW_JACOBIAN_PERIODS`], the fallback where the default
/// cannot make the fit) J is positive in every window and the fit recovers the offset.
#[test]
fn a_gait_bob_at_20_hz_turns_the_default_jacobian_negative_and_the_narrow_one_holds() {
    let dt_true = 0.137;
    let lever = Vector3::new(0.2, 0.1, 0.3);
    let sim = Sim::new(&|_| dt_true, &|t| 0.4 + 0.1 * (0.21 * t).sin(), lever)
        .bobbing(0.015, 4.5, dt_true);
    let jacobians = |data: &PoseData<'_>| -> Vec<f64> {
        let problem = data.problem();
        let d = lever * 1.02;
        data.windows()
            .iter()
            .filter_map(|w| {
                let t =
                    problem.terms(w, &ClockShape::Constant, &[dt_true], &d, false, 1.0 / 1.02)?;
                Some(t.j[(0, 0)])
            })
            .collect()
    };
    let default = sim.data();
    assert_eq!(default.params.jacobian_periods, JACOBIAN_PERIODS);
    let j = jacobians(&default);
    assert!(
        j.len() >= 4 && j.iter().filter(|&&j| j < 0.0).count() >= j.len() - 1,
        "{j:?}"
    );
    let w = default.windows();
    let f = fit(
        &default,
        &w,
        ClockShape::Constant,
        vec![dt_true + 0.03],
        Vector3::zeros(),
        true,
    );
    assert!(
        f.as_ref()
            .is_none_or(|f| !f.converged || (f.theta[0] - dt_true).abs() > 0.1),
        "{:?}",
        f.map(|f| f.theta)
    );
    let narrow = PoseData {
        params: PoseFitParams {
            jacobian_periods: NARROW_JACOBIAN_PERIODS,
            ..default.params
        },
        ..sim.data()
    };
    let j = jacobians(&narrow);
    assert!(j.len() >= 4 && j.iter().all(|&j| j > 0.0), "{j:?}");
    let f = constant_from(&narrow, &narrow.windows(), dt_true + 0.03);
    assert!((f.theta[0] - dt_true).abs() < 1e-3, "{:?}", f.theta);
}

/// Two position jumps of the estimate inside windows (0.8 m and 0.4 m) are two new frames, not
/// clock events: the offset stays within half a millisecond and the windows holding them are
/// fitted.
#[test]
fn a_jump_of_the_estimate_does_not_move_the_offset() {
    let dt_true = 0.137;
    let lever = Vector3::new(0.3, 0.0, 0.2);
    let sim = Sim::new(&|_| dt_true, &|t| 1.0 + 0.5 * (0.21 * t).sin(), lever)
        .jumped(31.03, Vector3::new(0.6, -0.5, 0.1))
        .jumped(79.51, Vector3::new(-0.3, 0.25, 0.0));
    assert_eq!(sim.jumps.len(), 2, "{:?}", sim.jumps);
    let data = sim.data();
    let w = data.windows();
    let f = constant_from(&data, &w, 0.1);
    assert!((f.theta[0] - dt_true).abs() < 5e-4, "{:?}", f.theta);
    // The windows holding the jumps are fitted, not set aside (noise-free, the residuals are
    // nanometres everywhere, so which window counts as an outlier is numerical noise).
    for jump_s in [31.03 + dt_true, 79.51 + dt_true] {
        assert!(f
            .windows
            .iter()
            .any(|w| w.t_start < jump_s && jump_s < w.t_end));
    }
    assert!(f.converged);
}

/// White noise on the reference, drawn again and again: the formal σ of Δt is the spread of its
/// answers; the σ the fit reports (the jackknife over five windows, floored by the formal σ) is
/// never below it and at most two thirds above it.
#[test]
fn the_sigma_of_the_offset_is_the_spread_of_its_answers() {
    use rand::SeedableRng;
    let dt_true = 0.137;
    let lever = Vector3::new(0.3, 0.0, 0.2);
    let clean = Sim::new(&|_| dt_true, &|t| 1.0 + 0.5 * (0.21 * t).sin(), lever);
    let (mut errors2, mut sigmas2, mut formal2) = (0.0, 0.0, 0.0);
    for seed in 0..40 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let sim = clean.clone().reference_noise(&mut rng, 0.03);
        let data = sim.data();
        let w = data.windows();
        let f = constant_from(&data, &w, 0.1);
        let problem = data.problem();
        let shared = SharedFit::new(&problem, &f.windows, &ClockShape::Constant, true);
        let terms = shared.eval(&f.theta, &f.lever_m, f.scale);
        let l = lever_weight(&terms);
        let jac = shared.jacobians((&f.theta, &f.lever_m, f.scale), &terms, l, f.jacobian_scale);
        let (h, _, _) = shared.summed(&terms, &f.lever_m, l, 1.0);
        let formal = shared.formal_covariance(&terms, &jac, &h).unwrap();
        assert!(f.theta_sigma[0] >= 0.999 * formal[(0, 0)].sqrt());
        // The pieces kept apart: θ's σ is the larger of its jackknife and its formal σ.
        let (jack, formal_k) = (f.theta_jackknife_sigma[0], f.theta_formal_sigma[0]);
        assert!((formal_k - formal[(0, 0)].sqrt()).abs() <= 1e-12 * formal_k.max(1e-9));
        let larger = if jack > 0.0 {
            jack.max(formal_k)
        } else {
            formal_k
        };
        assert!((f.theta_sigma[0] - larger).abs() <= 1e-12 * larger.max(1e-9));
        errors2 += (f.theta[0] - dt_true).powi(2);
        sigmas2 += f.theta_sigma[0].powi(2);
        formal2 += formal[(0, 0)];
    }
    // White residuals: the formal σ is the spread itself; the reported one (the jackknife of
    // five windows where it is larger) somewhat above it.
    let formal = (errors2 / formal2).sqrt();
    assert!(
        (0.75..1.33).contains(&formal),
        "RMS error / RMS formal σ {formal}"
    );
    let reported = (errors2 / sigmas2).sqrt();
    assert!(
        (0.6..1.0).contains(&reported),
        "RMS error / RMS σ {reported}"
    );
}

/// The estimate (20 Hz) stamped at receipt (each stamp late by an exponential latency of 15 ms
/// mean, re-ordered by stamp), the reference noisy, drawn again and again: the σ the fit reports
/// covers the spread of its answers and is not far wider. The error bar's Jacobian is measured on
/// the equations; with H = Σ v·v in the jackknife and the secant-scaled Jacobian in its floor (the
/// rule for this rate before; a scratch build of it), σ was short: RMS error over RMS σ 1.63 over
/// these draws, 0.84 measured.
#[test]
fn the_sigma_covers_the_spread_when_the_estimate_is_stamped_at_receipt() {
    use rand::SeedableRng;
    let dt_true = 0.137;
    let lever = Vector3::new(0.3, 0.0, 0.2);
    let clean = Sim::new(&|_| dt_true, &|t| 1.0 + 0.5 * (0.21 * t).sin(), lever);
    let latency = rand_distr::Exp::new(1.0 / 0.015).unwrap();
    let (mut errors2, mut sigmas2) = (0.0, 0.0);
    for seed in 0..30 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(100 + seed);
        let sim = clean
            .clone()
            .reference_noise(&mut rng, 0.01)
            .stamped_at_receipt(&mut rng, &latency);
        let data = sim.data();
        let w = data.windows();
        let f = constant_from(&data, &w, 0.1);
        // The truth includes the mean latency (part of the offset by definition).
        errors2 += (f.theta[0] - (dt_true - 0.015)).powi(2);
        sigmas2 += f.theta_sigma[0].powi(2);
    }
    let ratio = (errors2 / sigmas2).sqrt();
    assert!((0.5..1.1).contains(&ratio), "RMS error / RMS σ {ratio}");
}

/// At a constant walking speed a clock step leaves the speed signals nothing to locate it by;
/// the positions do: the change time is found to a fraction of a second.
#[test]
fn locates_a_step_at_constant_speed() {
    let lever = Vector3::new(0.3, 0.0, 0.2);
    let dt = |t: f64| if t < 60.0 { 0.437 } else { 0.137 };
    let sim = Sim::new(&dt, &|_| 0.5, lever);
    let located = locate_change(
        &sim.data(),
        &(lever * 1.02),
        1.02,
        (0.437, 0.137),
        (40.0, 80.0),
    )
    .unwrap();
    assert!((located - 60.0).abs() < 0.5, "{located}");
}

#[test]
fn scatter_factor_of_honest_sigmas_is_near_one() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let n = Normal::new(0.0, 1.0).unwrap();
    let w: Vec<(f64, f64, f64)> = (0..4000)
        .map(|k| {
            (
                k as f64 * 20.0,
                0.3 + 1e-5 * k as f64 + 0.004 * n.sample(&mut rng),
                0.004,
            )
        })
        .collect();
    let f = scatter_factor(&w);
    assert!((f - 1.0).abs() < 0.05, "{f}");
    let w3: Vec<(f64, f64, f64)> = w.iter().map(|&(t, d, s)| (t, d, s / 3.0)).collect();
    assert!((scatter_factor(&w3) - 3.0).abs() < 0.15);
}

/// Windows whose errors are (f·s)² + τ² in variance: the calibration recovers f and τ, and a
/// non-finite window does not poison it.
#[test]
fn scatter_calibration_recovers_a_factor_and_an_excess() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let n = Normal::new(0.0, 1.0).unwrap();
    let mut windows = |factor: f64, extra_s: f64| -> Vec<(f64, f64, f64)> {
        (0..4000)
            .map(|k| {
                // Least-squares σ from 1 to 6 ms, as sharp and dull windows alternate.
                let s = 0.001 * (1.0 + (k % 6) as f64);
                let sd = (factor * s).hypot(extra_s);
                (
                    k as f64 * 20.0,
                    0.3 + 1e-5 * k as f64 + sd * n.sample(&mut rng),
                    s,
                )
            })
            .collect()
    };
    let c = scatter_calibration(&windows(1.0, 0.002));
    assert!(
        (c.factor - 1.0).abs() < 0.1 && (c.extra_s - 0.002).abs() < 0.0003,
        "{c:?}"
    );
    let c = scatter_calibration(&windows(2.0, 0.0));
    assert!((c.factor - 2.0).abs() < 0.1 && c.extra_s < 0.0005, "{c:?}");
    let c = scatter_calibration(&windows(1.5, 0.003));
    assert!(
        (c.factor - 1.5).abs() < 0.15 && (c.extra_s - 0.003).abs() < 0.0005,
        "{c:?}"
    );
    // Honest σ: nothing added.
    let honest = scatter_calibration(&windows(1.0, 0.0));
    assert!(
        honest.factor < 1.05 && honest.extra_s < 0.0005,
        "{honest:?}"
    );
    // A NaN offset and an infinite σ among them: set aside, the answer finite.
    let mut w = windows(1.0, 0.002);
    w[10].1 = f64::NAN;
    w[20].2 = f64::INFINITY;
    let c = scatter_calibration(&w);
    assert!(
        c.factor.is_finite() && (c.extra_s - 0.002).abs() < 0.0003,
        "{c:?}"
    );
}

/// A walking robot whose body bobs 1.5 cm at 4.6 Hz, seen by a 10 Hz reference and a 10 Hz
/// estimate: the bob lies at 0.46 of the estimate's rate, where no cubic follows it, and every
/// reference sample falls at the same fraction of the estimate's period, so the misfit is the same
/// in every window. Compared point by point (the averaging off: its slow twin) Δt is pulled 10 ms;
/// on the reference's samples averaged over two of the estimate's periods ([`AVERAGE_BELOW_HZ`],
/// the default at 10 Hz) it is within a millisecond. Without the bob both agree with the truth:
/// the averaging changes no parameter of a model that holds.
#[test]
fn a_gait_at_the_estimates_nyquist_band_is_averaged_out() {
    let dt_true = 0.137;
    let lever = Vector3::new(0.2, 0.1, 0.3);
    let speed = |t: f64| 0.4 + 0.1 * (0.21 * t).sin();
    // Each reference sample 30 % of the way from one of the estimate's samples to the next.
    let walk = Sim::from(&|_| dt_true, &speed, lever, 1.03);
    let offsets = |sim: &Sim| {
        let data = sim.data();
        assert_eq!(data.params.average_below_hz, AVERAGE_BELOW_HZ);
        let point_by_point = PoseData {
            params: PoseFitParams {
                average_below_hz: 0.0,
                ..data.params
            },
            ..sim.data()
        };
        let offset = |data: &PoseData<'_>| {
            constant_from(data, &data.windows(), dt_true + 0.01).theta[0] - dt_true
        };
        (offset(&data), offset(&point_by_point))
    };
    let (averaged, raw) = offsets(&walk.clone().bobbing(0.015, 4.6, dt_true).thinned(2));
    assert!(averaged.abs() < 1e-3, "averaged {averaged}");
    assert!(raw.abs() > 5e-3, "point by point {raw}");
    let (averaged, raw) = offsets(&walk.thinned(2));
    assert!(
        averaged.abs() < 5e-4 && raw.abs() < 5e-4,
        "{averaged} {raw}"
    );
}

/// A vehicle at a steady speed but for one window where it nearly stops, its estimate stamped at
/// receipt, a 2 Hz reference: the jackknife's one step without a window (S − S_k, measured slopes)
/// can run far beyond the probe step its slopes were measured over. Those windows' delete-one fits
/// are made in full, so the jackknife's σ stays within twice its slow twin's (every delete-one fit
/// made in full); by one step alone it was 2.5–8.5 times the twin's on five of these twelve draws.
#[test]
fn the_jackknife_refits_a_window_whose_one_step_runs_away() {
    use rand::SeedableRng;
    let dt_true = 0.137;
    let lever = Vector3::new(0.3, 0.0, 0.2);
    let speed = |t: f64| {
        if (44.0..56.0).contains(&t) {
            1.5 - 1.45 * (std::f64::consts::PI * (t - 44.0) / 12.0).sin()
        } else {
            1.5
        }
    };
    let latency = rand_distr::Exp::new(1.0 / 0.015).unwrap();
    for seed in 0..12 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(700 + seed);
        let sim = Sim::new(&|_| dt_true, &speed, lever)
            .reference_noise(&mut rng, 0.01)
            .stamped_at_receipt(&mut rng, &latency)
            .reference_thinned(5);
        let data = sim.data();
        let f = constant_from(&data, &data.windows(), 0.1);
        // The slow twin: each window left out and the fit made again in full from the solution.
        let left_out: Vec<f64> = (0..f.windows.len())
            .filter_map(|k| {
                let mut others = f.windows.clone();
                others.remove(k);
                let shape = ClockShape::Constant;
                fit(&data, &others, shape, f.theta.clone(), f.lever_m, true).map(|g| g.theta[0])
            })
            .collect();
        let kf = left_out.len() as f64;
        let mean = left_out.iter().sum::<f64>() / kf;
        let spread = left_out.iter().map(|x| (x - mean).powi(2)).sum::<f64>();
        let twin = ((kf - 1.0) / kf * spread).sqrt();
        let jackknife = f.theta_jackknife_sigma[0];
        assert!(
            jackknife <= 2.0 * twin,
            "seed {seed}: {jackknife} against {twin}"
        );
    }
}

proptest::proptest! {
    /// Every tiling holds every reference sample in exactly one window, in order, each window
    /// between half a window and one and a half long; phase 0 is the mission's windows.
    #[test]
    fn every_tiling_covers_the_span_once_with_windows_half_to_one_and_a_half_long(
        span_s in 30.0f64..900.0,
        rate_hz in proptest::sample::select(vec![1.0, 2.0, 5.0, 20.0]),
        window_s in 10.0f64..40.0,
        phase in 0.0f64..1.0,
    ) {
        let t: Vec<f64> = (0..=(span_s * rate_hz) as usize).map(|k| k as f64 / rate_hz).collect();
        let base = windows(&t, Some(window_s));
        proptest::prop_assume!(!base.is_empty());
        let len = base[0].t_end - base[0].t_start;
        let w = tiling(&t, Some(window_s), phase);
        proptest::prop_assert_eq!(w[0].range.start, 0);
        proptest::prop_assert_eq!(w[w.len() - 1].range.end, t.len());
        for pair in w.windows(2) {
            proptest::prop_assert_eq!(pair[0].range.end, pair[1].range.start);
        }
        for x in &w {
            let l = x.t_end - x.t_start;
            proptest::prop_assert!(l >= 0.5 * len - 1e-6 && l <= 1.5 * len + 1e-6, "{} of {}", l, len);
        }
        let zero: Vec<_> = tiling(&t, Some(window_s), 0.0).iter().map(|x| x.range.clone()).collect();
        let base: Vec<_> = base.iter().map(|x| x.range.clone()).collect();
        proptest::prop_assert_eq!(zero, base);
    }
}

/// A vehicle whose speed changes slowly, a 2 Hz reference, its 20 Hz estimate stamped at receipt
/// (9 ms of mean latency), 110 s: Δt and the forward lever are nearly one direction of the
/// equations, told apart by the slow speed changes only, and the error bar's slope in Δt decides
/// how far. Measured over ±25 ms, a few of the stamps' jitter, the slope's noise decided it: over
/// these eight draws the errors (RMS 180 ms) were up to 12σ (−375 ms under σ 31 ms), RMS error
/// over RMS σ 2.0. Over [`PROBE_JITTERS`] of the jitter every error lies within 2σ.
#[test]
fn the_sigma_of_a_jittered_vehicle_covers_its_errors() {
    use rand::SeedableRng;
    let dt_true = 0.137;
    let lever = Vector3::new(0.3, 0.1, 0.0);
    let clean = Sim::new(&|_| dt_true, &|t| 1.9 + 0.4 * (0.05 * t).sin(), lever);
    let mean_s = 0.009;
    let latency = rand_distr::Exp::new(1.0 / mean_s).unwrap();
    let (mut errors2, mut sigmas2) = (0.0, 0.0);
    for seed in 0..8 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(900 + seed);
        let sim = clean
            .clone()
            .reference_noise(&mut rng, 0.02)
            .stamped_at_receipt(&mut rng, &latency)
            .reference_thinned(5);
        let data = sim.data();
        let f = constant_from(&data, &data.windows(), 0.1);
        // The truth includes the mean latency (part of the offset by definition).
        let error = f.theta[0] - (dt_true - mean_s);
        assert!(
            error.abs() <= 2.0 * f.theta_sigma[0],
            "seed {seed}: error {error} under σ {}",
            f.theta_sigma[0]
        );
        errors2 += error * error;
        sigmas2 += f.theta_sigma[0].powi(2);
    }
    let ratio = (errors2 / sigmas2).sqrt();
    assert!((0.4..1.2).contains(&ratio), "RMS error / RMS σ {ratio}");
}

//! A source's lever arm relative to the reference point.
//!
//! **With orientation** (odometry, poses): a least-squares fit of the 3-D lever ℓ together with a
//! correction δ of Δt. The source's frame differs from the reference's by an unknown similarity that
//! an odometry's drift changes slowly, so the mission is cut into windows of [`WINDOW_S`] and each
//! window gets its own (Umeyama's Sim(3)): p_ref(t) ≈ s_w·Q_w·(p_src(t − δ) − R_src(t)·ℓ) + c_w, with ℓ
//! the source's sensor relative to the reference point in the source's body frame (x forward, y left,
//! z up), `lever_m`, and t − δ the source's stamp of reference time t. Alternation: windows' similarities for
//! the current (ℓ, δ), then one Gauss–Newton step of (ℓ, δ) over all windows, centred per window so
//! that the windows' translations drop out; until the step is below 0.1 mm and 10 µs. σ: a jackknife
//! over windows of the final step (the windows are independent stretches of the mission, so their
//! spread is honest about correlated errors that a sample count would hide).
//!
//! **What the path can tell.** Turning informs the horizontal lever; tilting the vertical one (a
//! planar mission never tilts: z is `null`). A forward lever Δx and Δt are told apart only by changes
//! of speed: at a constant speed v a sensor Δx ahead is a sensor Δx/v early. When the fit's δ and ℓ_x
//! correlate beyond [`INSEPARABLE_CORRELATION`], the fit says so (`forward_separable: false`) and keeps
//! the report's Δt.
//!
//! **Positions only** (a prism, a GNSS): lateral from the Drift Error's lever fit (L_est = s·(L_ref −
//! d·Δψ)), forward from the lead of curvature over speed (`implied_lever_arm_m` of the time offset,
//! when `auto` found one), vertical unknown. Separable when the speed method was confident (speed is
//! blind to a forward lever; a path without speed changes gives it nothing to lock on).

use nalgebra::{Matrix3, Matrix4, SymmetricEigen, UnitQuaternion, Vector3, Vector4};

use super::report::{LeverFit, LeverMethod};
use crate::metrics::standard::umeyama::umeyama;
use crate::report::json::EstimateReport;
use crate::trajectory::Trajectory;

/// Window of one similarity, seconds.
pub const WINDOW_S: f64 = 30.0;
/// Fewest samples in a window.
pub const MIN_WINDOW_SAMPLES: usize = 20;
/// |corr(δ, ℓ_x)| above which a forward lever and Δt are said to be inseparable.
pub const INSEPARABLE_CORRELATION: f64 = 0.95;
/// A source sample pair further apart than this is a gap (no interpolation across it), seconds.
pub const MAX_GAP_S: f64 = 0.5;
/// The vertical lever is observable only when the body tilts: the RMS angle of its up axis about
/// its mean must reach this (2°; a 0.3 m vertical lever then moves 1 cm, above the noise).
pub const MIN_TILT_RAD: f64 = 0.035;

/// One reference sample with the source interpolated at its time.
struct Sample {
    window: usize,
    p_ref: Vector3<f64>,
    p_src: Vector3<f64>,
    v_src: Vector3<f64>,
    r_src: Matrix3<f64>,
}

/// The source at `t` (ns, reference clock): position, velocity (m/s) and orientation, interpolated
/// between the two samples around it; `None` in a gap or outside.
fn at(
    src: &Trajectory,
    q: &[UnitQuaternion<f64>],
    t: i64,
) -> Option<(Vector3<f64>, Vector3<f64>, Matrix3<f64>)> {
    let s = &src.stamps_ns;
    let k = s.partition_point(|&x| x <= t);
    if k == 0 || k >= s.len() {
        return None;
    }
    let (t0, t1) = (s[k - 1], s[k]);
    let dt = (t1 - t0) as f64 * 1e-9;
    if dt <= 0.0 || dt > MAX_GAP_S {
        return None;
    }
    let f = (t - t0) as f64 * 1e-9 / dt;
    let (p0, p1) = (src.positions[k - 1], src.positions[k]);
    let r = q[k - 1].slerp(&q[k], f);
    Some((
        p0 + (p1 - p0) * f,
        (p1 - p0) / dt,
        *r.to_rotation_matrix().matrix(),
    ))
}

/// The samples at correction `delta_s`, windowed from `t_first`.
fn samples(reference: &Trajectory, src: &Trajectory, delta_s: f64) -> Vec<Sample> {
    let Some(q) = src.orientations.as_deref() else {
        return Vec::new();
    };
    let d = (delta_s * 1e9).round() as i64;
    let t_first = reference.stamps_ns.first().copied().unwrap_or(0);
    reference
        .stamps_ns
        .iter()
        .zip(&reference.positions)
        .filter_map(|(&t, p)| {
            let (p_src, v_src, r_src) = at(src, q, t - d)?;
            Some(Sample {
                window: ((t - t_first) as f64 * 1e-9 / WINDOW_S) as usize,
                p_ref: *p,
                p_src,
                v_src,
                r_src,
            })
        })
        .collect()
}

/// Per window: the normal equations of the centred step (N_w, b_w) and the residual sum of squares.
struct WindowEquations {
    n: Matrix4<f64>,
    b: Vector4<f64>,
}

/// The windows' equations at (ℓ, δ): each window's similarity, then the centred linearisation.
fn equations(all: &[Sample], lever: &Vector3<f64>) -> Vec<WindowEquations> {
    let mut out = Vec::new();
    let mut start = 0;
    while start < all.len() {
        let w = all[start].window;
        let end = start + all[start..].iter().take_while(|s| s.window == w).count();
        let win = &all[start..end];
        start = end;
        if win.len() < MIN_WINDOW_SAMPLES {
            continue;
        }
        let x: Vec<Vector3<f64>> = win.iter().map(|s| s.p_src - s.r_src * lever).collect();
        let y: Vec<Vector3<f64>> = win.iter().map(|s| s.p_ref).collect();
        // A window on a straight line leaves its rotation about that line free: skipped.
        let spread = {
            let m = x.iter().fold(Vector3::zeros(), |a, p| a + p) / x.len() as f64;
            let c = x
                .iter()
                .fold(Matrix3::zeros(), |a, p| a + (p - m) * (p - m).transpose());
            let mut e: Vec<f64> = c.symmetric_eigenvalues().iter().copied().collect();
            e.sort_by(f64::total_cmp);
            e[1] / e[2].max(1e-12)
        };
        if spread < 1e-3 {
            continue;
        }
        let Ok(sim) = umeyama(&x, &y, true) else {
            continue;
        };
        let a = sim.rotation * sim.scale;
        // J_i = sQ·[−v_i, −R_i]; e_i = p_ref − (sQ x_i + c).
        let rows: Vec<(nalgebra::Matrix3x4<f64>, Vector3<f64>)> = win
            .iter()
            .zip(&x)
            .map(|(s, xi)| {
                let mut j = nalgebra::Matrix3x4::zeros();
                // p_src(t − δ): its derivative in δ is −v.
                j.set_column(0, &(-(a * s.v_src)));
                let r = -(a * s.r_src);
                for c in 0..3 {
                    j.set_column(c + 1, &r.column(c));
                }
                (j, s.p_ref - (a * xi + sim.translation))
            })
            .collect();
        let nf = rows.len() as f64;
        let (mj, me) = rows.iter().fold(
            (nalgebra::Matrix3x4::zeros(), Vector3::zeros()),
            |(mj, me), (j, e)| (mj + j, me + e),
        );
        let (mj, me) = (mj / nf, me / nf);
        let mut n = Matrix4::zeros();
        let mut b = Vector4::zeros();
        for (j, e) in &rows {
            let (jc, ec) = (j - mj, e - me);
            n += jc.transpose() * jc;
            b += jc.transpose() * ec;
        }
        out.push(WindowEquations { n, b });
    }
    out
}

/// Eigenvalues of the unit-diagonal normal matrix below this share of the largest are its null
/// space: a parameter that lies there is not observable (0.001: a correlation of 0.999 with the
/// others).
pub const NULL_EIGENVALUE: f64 = 1e-3;

/// The pseudo-inverse of a normal matrix after scaling it to a unit diagonal, and which parameters
/// lie in its null space (not observable). Parameters marked `fixed` are held (no row, no column).
fn pseudo_inverse(n: &Matrix4<f64>, fixed: [bool; 4]) -> (Matrix4<f64>, [bool; 4]) {
    let mut n = *n;
    for k in 0..4 {
        if fixed[k] {
            for j in 0..4 {
                n[(k, j)] = 0.0;
                n[(j, k)] = 0.0;
            }
        }
    }
    let n = &n;
    let d: Vec<f64> = (0..4).map(|k| n[(k, k)].max(1e-300).sqrt()).collect();
    let dm = Matrix4::from_diagonal(&Vector4::new(
        1.0 / d[0],
        1.0 / d[1],
        1.0 / d[2],
        1.0 / d[3],
    ));
    let scaled = dm * n * dm;
    let eig = SymmetricEigen::new(scaled);
    let max = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut inv = Matrix4::zeros();
    let mut null = [0.0; 4];
    for k in 0..4 {
        let v = eig.eigenvectors.column(k);
        if eig.eigenvalues[k] > NULL_EIGENVALUE * max && max > 0.0 {
            inv += v * v.transpose() / eig.eigenvalues[k];
        } else {
            for (i, x) in null.iter_mut().enumerate() {
                *x += v[i] * v[i];
            }
        }
    }
    let unobservable = [0, 1, 2, 3].map(|i| fixed[i] || null[i] > 0.5 || n[(i, i)] <= 0.0);
    let mut inv = dm * inv * dm;
    for k in 0..4 {
        if fixed[k] {
            for j in 0..4 {
                inv[(k, j)] = 0.0;
                inv[(j, k)] = 0.0;
            }
        }
    }
    (inv, unobservable)
}

/// The pose fit of `src` (its stamps already on the reference clock, with orientations) against the
/// reference's positions. `None` when too few windows can be fitted.
pub fn pose_fit(reference: &Trajectory, src: &Trajectory, offset_s: f64) -> Option<LeverFit> {
    src.orientations.as_ref()?;
    // The vertical lever needs the body to tilt (see MIN_TILT_RAD): held at 0 otherwise.
    let fixed = [false, false, false, tilt_rad(reference, src) < MIN_TILT_RAD];
    let (lever, delta, eqs, inv, mut unobservable) = gauss_newton(reference, src, fixed)?;
    // A lever beyond a robot's size is a fit that did not settle: not observable.
    for k in 0..3 {
        if lever[k].abs() > 5.0 {
            unobservable[k + 1] = true;
        }
    }
    let sigma = jackknife_sigma(&eqs, fixed);
    let corr = inv[(0, 1)] / (inv[(0, 0)] * inv[(1, 1)]).sqrt().max(1e-300);
    let forward_separable = !unobservable[0]
        && !unobservable[1]
        && corr.is_finite()
        && corr.abs() < INSEPARABLE_CORRELATION;
    let component = |k: usize, v: f64| (!unobservable[k + 1]).then_some(v);
    let lever_m = [
        component(0, lever.x),
        component(1, lever.y),
        component(2, lever.z),
    ];
    let sigma_m = [0, 1, 2].map(|k| component(k, sigma[k + 1]));
    let mut note = format!(
        "fitted on {} windows of {WINDOW_S:.0} s with Δt {:+.4} s ({:+.1} ms from the clock model)",
        eqs.len(),
        offset_s + delta,
        delta * 1e3
    );
    if unobservable[3] {
        note.push_str("; the path never tilts, so the vertical lever is unknown");
    }
    if !forward_separable {
        note.push_str(&format!(
            "; the speed hardly changes, so a forward lever cannot be told from Δt (correlation {corr:+.2}): a sensor Δx ahead looks Δx/v early"
        ));
    }
    Some(LeverFit {
        method: LeverMethod::PoseFit,
        lever_m,
        sigma_m,
        dt_s: Some(offset_s + delta),
        dt_sigma_s: (!unobservable[0]).then_some(sigma[0]),
        forward_separable,
        windows: eqs.len(),
        note,
    })
}

/// The spread of the body's up axis over the mission, radians.
fn tilt_rad(reference: &Trajectory, src: &Trajectory) -> f64 {
    let ups: Vec<Vector3<f64>> = samples(reference, src, 0.0)
        .iter()
        .map(|s| s.r_src * Vector3::z())
        .collect();
    let mean_up = ups.iter().sum::<Vector3<f64>>() / ups.len().max(1) as f64;
    (ups.iter()
        .map(|u| (u - mean_up).norm_squared())
        .sum::<f64>()
        / ups.len().max(1) as f64)
        .sqrt()
}

type Solution = (
    Vector3<f64>,
    f64,
    Vec<WindowEquations>,
    Matrix4<f64>,
    [bool; 4],
);

/// Gauss–Newton on (Δt correction, lever): the lever, the Δt correction, the windows' equations at
/// the solution, the normal matrix's pseudo-inverse and which unknowns are unobservable.
fn gauss_newton(reference: &Trajectory, src: &Trajectory, fixed: [bool; 4]) -> Option<Solution> {
    let mut lever = Vector3::zeros();
    let mut delta = 0.0;
    let mut last: Option<(Vec<WindowEquations>, Matrix4<f64>, [bool; 4])> = None;
    for _ in 0..20 {
        let s = samples(reference, src, delta);
        let eqs = equations(&s, &lever);
        if eqs.len() < 3 {
            return None;
        }
        let n: Matrix4<f64> = eqs.iter().map(|e| e.n).sum();
        let b: Vector4<f64> = eqs.iter().map(|e| e.b).sum();
        let (inv, unobservable) = pseudo_inverse(&n, fixed);
        let step = inv * b;
        // Steps bounded (0.5 s, 1 m) so that one poor linearisation cannot throw the fit away.
        delta += step[0].clamp(-0.5, 0.5);
        let dl = Vector3::new(step[1], step[2], step[3]);
        lever += dl * (1.0 / dl.norm().max(1.0));
        let done = step[0].abs() < 1e-5 && dl.norm() < 1e-4;
        last = Some((eqs, inv, unobservable));
        if done {
            break;
        }
    }
    let (eqs, inv, unobservable) = last?;
    Some((lever, delta, eqs, inv, unobservable))
}

/// σ of the four unknowns by a jackknife over the windows of the linearised problem at the solution.
fn jackknife_sigma(eqs: &[WindowEquations], fixed: [bool; 4]) -> Vector4<f64> {
    let n_all: Matrix4<f64> = eqs.iter().map(|e| e.n).sum();
    let b_all: Vector4<f64> = eqs.iter().map(|e| e.b).sum();
    let w = eqs.len() as f64;
    let leave_out: Vec<Vector4<f64>> = eqs
        .iter()
        .map(|e| pseudo_inverse(&(n_all - e.n), fixed).0 * (b_all - e.b))
        .collect();
    let mean = leave_out.iter().sum::<Vector4<f64>>() / w;
    let var = leave_out
        .iter()
        .map(|x| (x - mean).component_mul(&(x - mean)))
        .sum::<Vector4<f64>>()
        * ((w - 1.0) / w);
    var.map(f64::sqrt)
}

/// The lever from positions alone, from a source's evaluation against the reference.
pub fn positions_lever(e: &EstimateReport) -> LeverFit {
    let lateral = e.drift_error.first().and_then(|d| d.lateral_lever_m);
    let forward = e.time_offset.implied_lever_arm_m;
    let speed_ok = e.time_offset.methods.iter().any(|m| {
        m.method == crate::align::time_offset::OffsetMethod::Speed
            && m.status == crate::report::json::MethodStatus::Ok
    });
    let mut note = String::from("from positions alone: ");
    note.push_str(match lateral {
        Some(_) => "lateral from the Drift Error's lever fit",
        None => "no lateral lever (no Drift Error lever fit)",
    });
    note.push_str(match forward {
        Some(_) => ", forward from the lead of curvature over speed",
        None => ", no forward lever seen (curvature and speed agree)",
    });
    note.push_str("; the vertical one needs orientation");
    if !speed_ok {
        note.push_str(
            "; the speed method was not confident, so a forward lever cannot be told from Δt",
        );
    }
    LeverFit {
        method: LeverMethod::Positions,
        lever_m: [forward.or(Some(0.0).filter(|_| speed_ok)), lateral, None],
        sigma_m: [None, None, None],
        dt_s: None,
        dt_sigma_s: None,
        forward_separable: speed_ok,
        windows: 0,
        note,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::motion::{integrate, state_at};
    use crate::simulate::{default_route, route_of_duration};

    /// A planar mission: the reference point's positions, and a source Δx ahead / to the left, its
    /// own frame rotated and moved, its stamps `late_s` late.
    fn mission(lever: [f64; 3], late_s: f64) -> (Trajectory, Trajectory) {
        let route = route_of_duration(&default_route(), 300.0);
        let states = integrate(&route, 1000.0, 0.4, 1.0);
        let duration = states.last().unwrap().t;
        let frame = nalgebra::Isometry3::new(Vector3::new(5.0, -3.0, 1.0), Vector3::z() * 1.1);
        let mut r = Trajectory::new(false);
        let mut s = Trajectory::new(true);
        let l = Vector3::from(lever);
        let mut k = 0.0;
        while k < duration {
            let b = state_at(&states, 1000.0, k);
            let q = UnitQuaternion::from_euler_angles(0.0, 0.0, b.yaw);
            r.push((k * 1e9) as i64, b.position, None);
            let p = frame * nalgebra::Point3::from(b.position + q * l);
            let stamp = ((k - late_s) * 1e9) as i64;
            s.push(stamp, p.coords, Some(frame.rotation * q));
            k += 0.1;
        }
        (r, s)
    }

    #[test]
    fn recovers_a_horizontal_lever_and_says_z_is_unknown() {
        let (r, s) = mission([0.4, -0.25, 0.3], 0.0);
        let f = pose_fit(&r, &s, 0.0).unwrap();
        assert!((f.lever_m[0].unwrap() - 0.4).abs() < 0.01, "{f:?}");
        assert!((f.lever_m[1].unwrap() + 0.25).abs() < 0.01, "{f:?}");
        assert_eq!(f.lever_m[2], None, "planar: z not observable");
        assert!(f.dt_s.unwrap().abs() < 0.005, "{f:?}");
        assert!(f.forward_separable, "{f:?}");
    }

    #[test]
    fn finds_a_residual_delay_together_with_the_lever() {
        // The clock model left 40 ms: the fit finds it beside the lever.
        let (r, s) = mission([0.3, 0.2, 0.0], 0.04);
        let f = pose_fit(&r, &s, 0.0).unwrap();
        assert!((f.dt_s.unwrap() - 0.04).abs() < 0.005, "{f:?}");
        assert!((f.lever_m[0].unwrap() - 0.3).abs() < 0.02, "{f:?}");
    }
}

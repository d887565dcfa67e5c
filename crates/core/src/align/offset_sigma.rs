//! The standard error of a time offset, from the data that gave it.
//!
//! A correlation peak says where the two signals agree best, not how well that place is pinned down.
//! Whether a drift of the clocks shows between the first and the last third of a mission depends on
//! exactly that: on a few minutes of driving the thirds' offsets scatter by tens of milliseconds, on
//! two hours by a few. So every offset gets a standard error, computed from its own residual.
//!
//! Linearising y(t) = a·x(t − δ) + r(t) around the peak (x the reference signal, y the estimate's,
//! both on the grid, shifted by the estimate), the least-squares shift is
//! δ̂ = −Σ x′·r / (a·Σ x′²), so var δ̂ = var(Σ x′·r) / (a·Σ x′²)². The residual r is not white: it
//! carries the speed window's smoothing and the systematic differences between two sensors (a
//! lateral lever arm changes the speed in every turn). Its variance is therefore taken by batch
//! means — var(Σ x′·r) ≈ Σ_b (Σ_{k∈b} x′_k·r_k)² over blocks of [`BLOCK_S`] seconds, longer than the
//! residual's correlation — which holds for any residual that decorrelates within a block. Either
//! signal may be the noisy one, so the slope is taken from each in turn and the larger error kept.
//!
//! What the residual cannot show is noise that has already moved the peak (at the peak it is no
//! longer in the residual): [`crate::align::offset_profile`] scales it by the scatter of the profile.

use crate::align::grid::{GridBlocks, LazyGrid};
use crate::align::xcorr::Centering;

/// Length of the blocks of the batch-means variance, seconds: longer than the speed window and than a
/// turn (the residual's correlation time), short enough for a third of a few-minute mission to hold
/// several.
pub const BLOCK_S: f64 = 10.0;
/// The fewest blocks the variance is taken from.
pub const MIN_BLOCKS: usize = 3;

/// The standard error of `offset_s`, seconds, for the signals `reference` and `estimate` (times,
/// values) compared on a grid of `step` with gaps longer than `max_gap_s` left undefined. `None` when
/// the overlap holds fewer than [`MIN_BLOCKS`] blocks or a signal is flat.
///
/// One pass over the grid, read a stretch at a time: every sum below is a running sum (globally and
/// per block), so no grid and no list of points is held, whatever the mission's length.
pub fn offset_sigma(
    (ref_t, ref_v): (&[f64], &[f64]),
    (est_t, est_v): (&[f64], &[f64]),
    offset_s: f64,
    step: f64,
    max_gap_s: f64,
    centering: Centering,
) -> Option<f64> {
    let x = LazyGrid::new(ref_t, ref_v, step, max_gap_s);
    let y = LazyGrid::shifted(est_t, est_v, step, max_gap_s, offset_s);
    let lo = x.first_index.max(y.first_index);
    let hi = (x.first_index + x.len() as i64).min(y.first_index + y.len() as i64);
    let block = (BLOCK_S / step).round().max(1.0) as i64;
    let mut sums = Sums::new(centering == Centering::MeanRemoved, block);
    // Grid points where both signals and both central differences are defined, a stretch at a time
    // (with one point either side for the differences).
    const STRETCH: i64 = 1 << 12;
    let len = (STRETCH + 2) as usize;
    let (mut xv, mut xm, mut yv, mut ym) = (
        vec![0.0; len],
        vec![0.0; len],
        vec![0.0; len],
        vec![0.0; len],
    );
    let mut start = lo + 1;
    while start < hi - 1 {
        let count = STRETCH.min(hi - 1 - start) as usize;
        x.read(
            start - 1 - x.first_index,
            &mut xv[..count + 2],
            &mut xm[..count + 2],
        );
        y.read(
            start - 1 - y.first_index,
            &mut yv[..count + 2],
            &mut ym[..count + 2],
        );
        for i in 1..=count {
            if xm[i - 1..=i + 1]
                .iter()
                .chain(&ym[i - 1..=i + 1])
                .all(|&m| m > 0.5)
            {
                let dx = (xv[i + 1] - xv[i - 1]) / (2.0 * step);
                let dy = (yv[i + 1] - yv[i - 1]) / (2.0 * step);
                sums.add(start + i as i64 - 1, (xv[i], yv[i]), (dx, dy));
            }
        }
        start += STRETCH;
    }
    if sums.count < 3 || sums.last_n - sums.first_n < MIN_BLOCKS as i64 * block {
        return None;
    }
    // Either signal may carry the noise (a GNSS reference is usually the noisier, an odometry
    // estimate the smoother): the slope is taken from one, the residual against the other, both
    // ways, and the larger error kept.
    match (
        sums.one_way(Direction::SlopeOfX),
        sums.one_way(Direction::SlopeOfY),
    ) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// Which signal the slope is taken from.
#[derive(Clone, Copy)]
enum Direction {
    SlopeOfX,
    SlopeOfY,
}

/// The running sums of one pass. Values are taken relative to the first point's when the means
/// are removed (shifted sums: no cancellation between Σu² and N·ū²).
struct Sums {
    centered: bool,
    block: i64,
    origin: (f64, f64),
    count: usize,
    first_n: i64,
    last_n: i64,
    /// Σx, Σy, Σx², Σy², Σxy, Σx′², Σy′².
    x: f64,
    y: f64,
    xx: f64,
    yy: f64,
    xy: f64,
    dxdx: f64,
    dydy: f64,
    /// Per block: Σx′·y, Σx′, Σx′·x, Σy′·x, Σy′, Σy′·y.
    blocks: Vec<[f64; 6]>,
}

impl Sums {
    fn new(centered: bool, block: i64) -> Self {
        Sums {
            centered,
            block,
            origin: (0.0, 0.0),
            count: 0,
            first_n: 0,
            last_n: 0,
            x: 0.0,
            y: 0.0,
            xx: 0.0,
            yy: 0.0,
            xy: 0.0,
            dxdx: 0.0,
            dydy: 0.0,
            blocks: Vec::new(),
        }
    }

    fn add(&mut self, n: i64, (x, y): (f64, f64), (dx, dy): (f64, f64)) {
        if self.count == 0 {
            self.first_n = n;
            if self.centered {
                self.origin = (x, y);
            }
        }
        self.count += 1;
        self.last_n = n;
        let (x, y) = (x - self.origin.0, y - self.origin.1);
        self.x += x;
        self.y += y;
        self.xx += x * x;
        self.yy += y * y;
        self.xy += x * y;
        self.dxdx += dx * dx;
        self.dydy += dy * dy;
        let b = ((n - self.first_n) / self.block) as usize;
        if self.blocks.len() <= b {
            self.blocks.resize(b + 1, [0.0; 6]);
        }
        let s = &mut self.blocks[b];
        for (acc, v) in s.iter_mut().zip([dx * y, dx, dx * x, dy * x, dy, dy * y]) {
            *acc += v;
        }
    }

    /// The standard error with the slope taken from one signal u, the residual of the other v
    /// against g·u: r = (v − v̄) − g·(u − ū), g the least-squares gain, and the batch means of
    /// z = u′·r, Σ_{k∈b} z_k = Σu′v − v̄·Σu′ − g·(Σu′u − ū·Σu′) per block.
    fn one_way(&self, direction: Direction) -> Option<f64> {
        let n = self.count as f64;
        let (su, sv, suu, sdd) = match direction {
            Direction::SlopeOfX => (self.x, self.y, self.xx, self.dxdx),
            Direction::SlopeOfY => (self.y, self.x, self.yy, self.dydy),
        };
        let (mu, mv) = if self.centered {
            (su / n, sv / n)
        } else {
            (0.0, 0.0)
        };
        let suu = suu - n * mu * mu;
        let suv = self.xy - n * mu * mv;
        if !(suu > 0.0 && sdd > 0.0) {
            return None;
        }
        let gain = suv / suu;
        let var_sum: f64 = self
            .blocks
            .iter()
            .map(|b| {
                let (duv, du, duu) = match direction {
                    Direction::SlopeOfX => (b[0], b[1], b[2]),
                    Direction::SlopeOfY => (b[3], b[4], b[5]),
                };
                let z = duv - mv * du - gain * (duu - mu * du);
                z * z
            })
            .sum();
        let sigma = var_sum.sqrt() / (gain.abs() * sdd);
        sigma.is_finite().then_some(sigma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A noisy copy of a smooth signal: the standard error matches the scatter of the offsets the
    /// linearised least squares would give, within a factor of two.
    #[test]
    fn white_noise_gives_the_textbook_error() {
        // x(t) = sin(0.7 t) + 0.5 sin(1.9 t), y = x + white noise σ_n, dense samples.
        let h = 0.01;
        let t: Vec<f64> = (0..20_000).map(|i| i as f64 * h).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| (0.7 * t).sin() + 0.5 * (1.9 * t).sin())
            .collect();
        let sigma_n = 0.1;
        // Deterministic pseudo-noise (LCG), uniform with the right variance.
        let mut s = 12345u64;
        let y: Vec<f64> = x
            .iter()
            .map(|&v| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                v + u * sigma_n * 12f64.sqrt()
            })
            .collect();
        let got = offset_sigma((&t, &x), (&t, &y), 0.0, h, 1.0, Centering::MeanRemoved).unwrap();
        // Textbook: σ_δ = σ_n / √(Σ x′²).
        let sdd: f64 = t
            .iter()
            .map(|&t| (0.7 * (0.7 * t).cos() + 0.95 * (1.9 * t).cos()).powi(2))
            .sum();
        let want = sigma_n / sdd.sqrt();
        assert!(got > 0.5 * want && got < 2.0 * want, "{got} vs {want}");
    }

    /// The definition, two passes over a list of points (what σ computed before it was streamed).
    fn two_pass(
        (rt, rv): (&[f64], &[f64]),
        (et, ev): (&[f64], &[f64]),
        offset_s: f64,
        step: f64,
        gap: f64,
        centering: Centering,
    ) -> Option<f64> {
        use crate::align::grid::resample;
        let x = resample(rt, rv, step, gap);
        let shifted: Vec<f64> = et.iter().map(|t| t + offset_s).collect();
        let y = resample(&shifted, ev, step, gap);
        let at = |s: &crate::align::grid::RegularSignal, n: i64| {
            let i = n - s.first_index;
            ((0..s.len() as i64).contains(&i) && s.mask[i as usize] > 0.5)
                .then(|| s.values[i as usize])
        };
        // (n, x, y, x′, y′) where both signals and both differences are defined.
        type Point = (i64, f64, f64, f64, f64);
        let pts: Vec<Point> = (x.first_index.min(y.first_index) - 2
            ..x.first_index.max(y.first_index) + x.len().max(y.len()) as i64 + 2)
            .filter_map(|n| {
                let xs = [at(&x, n - 1)?, at(&x, n)?, at(&x, n + 1)?];
                let ys = [at(&y, n - 1)?, at(&y, n)?, at(&y, n + 1)?];
                let d = |v: [f64; 3]| (v[2] - v[0]) / (2.0 * step);
                Some((n, xs[1], ys[1], d(xs), d(ys)))
            })
            .collect();
        let block = (BLOCK_S / step).round() as i64;
        if pts.len() < 3 || pts[pts.len() - 1].0 - pts[0].0 < MIN_BLOCKS as i64 * block {
            return None;
        }
        let one = |pick: &dyn Fn(&Point) -> (f64, f64, f64)| {
            let n = pts.len() as f64;
            let (mu, mv) = match centering {
                Centering::MeanRemoved => (
                    pts.iter().map(|p| pick(p).0).sum::<f64>() / n,
                    pts.iter().map(|p| pick(p).1).sum::<f64>() / n,
                ),
                Centering::Raw => (0.0, 0.0),
            };
            let suu: f64 = pts.iter().map(|p| (pick(p).0 - mu).powi(2)).sum();
            let suv: f64 = pts
                .iter()
                .map(|p| (pick(p).0 - mu) * (pick(p).1 - mv))
                .sum();
            let sdd: f64 = pts.iter().map(|p| pick(p).2.powi(2)).sum();
            let gain = suv / suu;
            let mut sums = vec![0.0; ((pts[pts.len() - 1].0 - pts[0].0) / block + 1) as usize];
            for p in &pts {
                let (u, v, d) = pick(p);
                sums[((p.0 - pts[0].0) / block) as usize] += d * ((v - mv) - gain * (u - mu));
            }
            sums.iter().map(|s| s * s).sum::<f64>().sqrt() / (gain.abs() * sdd)
        };
        Some(one(&|p| (p.1, p.2, p.3)).max(one(&|p| (p.2, p.1, p.4))))
    }

    /// The one-pass sums give the two-pass definition's σ, both centerings, with gaps, an offset and
    /// irregular samples on both sides.
    #[test]
    fn one_pass_matches_the_two_pass_definition() {
        let signal =
            |t: f64| 1.5 + (0.37 * t).sin() + 0.4 * (1.3 * t).sin() + 0.2 * (0.05 * t).cos();
        let rt: Vec<f64> = (0..9000)
            .map(|i| i as f64 * 0.1 + 0.003 * (i as f64 * 0.7).sin())
            .filter(|t| !(300.0..320.0).contains(t))
            .collect();
        let rv: Vec<f64> = rt
            .iter()
            .enumerate()
            .map(|(i, &t)| signal(t) + 0.01 * ((i * 7919 % 13) as f64 - 6.0))
            .collect();
        let et: Vec<f64> = (0..180_000).map(|i| 5.0 + i as f64 * 0.005).collect();
        let offset = 0.237;
        let ev: Vec<f64> = et.iter().map(|&t| signal(t + offset)).collect();
        for centering in [Centering::Raw, Centering::MeanRemoved] {
            let got = offset_sigma((&rt, &rv), (&et, &ev), offset, 0.02, 0.5, centering).unwrap();
            let want = two_pass((&rt, &rv), (&et, &ev), offset, 0.02, 0.5, centering).unwrap();
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "{centering:?}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn too_short_has_no_error() {
        let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        let x: Vec<f64> = t.iter().map(|t| t.sin()).collect();
        assert!(offset_sigma((&t, &x), (&t, &x), 0.0, 0.02, 1.0, Centering::Raw).is_none());
    }
}

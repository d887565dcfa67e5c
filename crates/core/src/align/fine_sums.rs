//! The fine stage's overlap sums: the six sums of the masked NCC at every fine lag, equal to summing
//! the two signals on their common fine grid (step δt, 1 ms by default) but at a cost that grows with
//! (samples of the sparser signal × lags) + (fine grid points), not (fine grid points × lags).
//!
//! Why: on a 2-hour mission the fine grid holds 7.2 M points; summing them at each of the 81 lags of
//! the fine window, for three methods and the offset profile, took most of an evaluation. Decimating
//! the sums instead (every 5–20 ms) moved Δt by up to 4.7 ms on the shared missions; this is the
//! same sum, reorganised.
//!
//! How: on the fine grid both signals are linear interpolations of their samples
//! ([`crate::align::grid`]). Between two consecutive samples of the sparser signal S its grid values
//! form a *run* c₀ + c₁·u (u = 0, 1, …). Against the denser signal D (values d, mask m) the sums over a
//! run are
//!
//! Σm, Σd, c₀Σm + c₁Σu·m, c₀Σd + c₁Σu·d, Σd², c₀²Σm + 2c₀c₁Σu·m + c₁²Σu²·m,
//!
//! range sums read from prefix sums of D's fine grid, built one block at a time. The mask's sums are
//! integers below 2⁵³ (exact in f64); the others use block-local indices, so their rounding stays near
//! 1e-12 of the sums (`tests` compares with the direct sums).

use crate::align::grid::resample_into;
use crate::align::xcorr::OverlapSums;

/// Dense fine-grid points per block (at least 4× the lag span): bounds the buffers on long missions and
/// keeps the mask's third-order prefix sums below 2⁵³. The eight buffers of a block (64 KB each) are
/// reused from block to block: allocated once per search, they stay in the cache.
const BLOCK: usize = 1 << 13;

/// Overlap sums at the lags `lo..=hi`, pairing `a` at grid point n with `b` at n + k (Δt = k·hf), as
/// if both were resampled on the grid t = n·hf with gaps longer than `gap` left undefined. Times
/// increasing, values finite.
pub fn fine_sums(
    (at, av): (&[f64], &[f64]),
    (bt, bv): (&[f64], &[f64]),
    hf: f64,
    gap: f64,
    lo: i64,
    hi: i64,
) -> Vec<OverlapSums> {
    let lags = (hi - lo + 1).max(0) as usize;
    if lags == 0 || at.is_empty() || bt.is_empty() || hf.is_nan() || hf <= 0.0 {
        return vec![OverlapSums::default(); lags];
    }
    if at.len() <= bt.len() {
        // a is the sparse one: (S at m, D at m + k).
        let s = sums_against_runs(&runs(at, av, hf, gap), (bt, bv), hf, gap, (lo, hi), 1);
        s.into_iter().map(|x| x.into_sums(false)).collect()
    } else {
        // b is the sparse one: (D at n, S at n + k), i.e. (S at m, D at m − k).
        let s = sums_against_runs(&runs(bt, bv, hf, gap), (at, av), hf, gap, (lo, hi), -1);
        s.into_iter().map(|x| x.into_sums(true)).collect()
    }
}

/// Grid points m0 … m0 + len − 1 of the sparse signal, valued c0 + c1·(m − m0).
#[derive(Debug, Clone, Copy)]
struct Run {
    m0: i64,
    len: usize,
    c0: f64,
    c1: f64,
}

/// The sums of one lag with S and D named (mapped onto a/b by [`Sums::into_sums`]).
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    n: f64,
    d: f64,
    s: f64,
    ds: f64,
    dd: f64,
    ss: f64,
}

impl Sums {
    /// `dense_is_a`: whether D is the signal called `a` in [`fine_sums`].
    fn into_sums(self, dense_is_a: bool) -> OverlapSums {
        let (sa, sb, saa, sbb) = if dense_is_a {
            (self.d, self.s, self.dd, self.ss)
        } else {
            (self.s, self.d, self.ss, self.dd)
        };
        OverlapSums {
            n: self.n,
            sa,
            sb,
            sab: self.ds,
            saa,
            sbb,
        }
    }
}

/// The smallest grid index m with m·hf ≥ t (the same products [`resample_into`] forms).
fn first_at_or_after(t: f64, hf: f64) -> i64 {
    let mut m = (t / hf).ceil() as i64;
    while ((m - 1) as f64) * hf >= t {
        m -= 1;
    }
    while (m as f64) * hf < t {
        m += 1;
    }
    m
}

/// The runs of the sparse signal on the fine grid, in order, each at most `BLOCK / 4` long. A grid
/// point belongs to the last sample at or before it (as in [`resample_into`]): equal to it
/// within 1e-9 of a step, it takes that sample's value; otherwise it interpolates towards the next
/// sample, unless they are more than `gap` apart or it is the last.
fn runs(t: &[f64], v: &[f64], hf: f64, gap: f64) -> Vec<Run> {
    let tol = 1e-9 * hf;
    let n = t.len().min(v.len());
    let mut out = Vec::with_capacity(n);
    let mut push = |m0: i64, len: usize, c0: f64, c1: f64| {
        let mut done = 0;
        while done < len {
            let l = (len - done).min(BLOCK / 4);
            out.push(Run {
                m0: m0 + done as i64,
                len: l,
                c0: c0 + c1 * done as f64,
                c1,
            });
            done += l;
        }
    };
    for i in 0..n {
        if i + 1 < n && t[i + 1] <= t[i] {
            // A repeated stamp: grid points from here on belong to the later sample.
            continue;
        }
        let mut m = first_at_or_after(t[i], hf);
        if (m as f64 * hf - t[i]).abs() <= tol {
            push(m, 1, v[i], 0.0);
            m += 1;
        }
        if i + 1 >= n {
            break;
        }
        let g = t[i + 1] - t[i];
        if g > gap || g <= 0.0 {
            continue;
        }
        let end = first_at_or_after(t[i + 1], hf);
        if end > m {
            let slope = (v[i + 1] - v[i]) / g;
            push(
                m,
                (end - m) as usize,
                v[i] + (m as f64 * hf - t[i]) * slope,
                hf * slope,
            );
        }
    }
    out
}

/// Prefix sums over one block of D's fine grid (local index q): of the mask (orders 0–2), of the
/// values (orders 0–1) and of the squared values.
struct Prefix {
    m0: Vec<f64>,
    m1: Vec<f64>,
    m2: Vec<f64>,
    d0: Vec<f64>,
    d1: Vec<f64>,
    dd: Vec<f64>,
}

impl Prefix {
    /// Empty prefix sums, with room for blocks of `n` points.
    fn with_capacity(n: usize) -> Prefix {
        let v = || Vec::with_capacity(n + 1);
        Prefix {
            m0: v(),
            m1: v(),
            m2: v(),
            d0: v(),
            d1: v(),
            dd: v(),
        }
    }

    /// The prefix sums of one block (values, mask), in place of the previous block's: the buffers
    /// are reused from block to block.
    fn fill(&mut self, values: &[f64], mask: &[f64]) {
        let n = values.len().min(mask.len());
        for v in [
            &mut self.m0,
            &mut self.m1,
            &mut self.m2,
            &mut self.d0,
            &mut self.d1,
            &mut self.dd,
        ] {
            v.clear();
            v.resize(n + 1, 0.0);
        }
        // Written by index into buffers of the final length (no push, no branch per point); every
        // slice n long, so that the bounds checks fold away.
        let (mask, values) = (&mask[..n], &values[..n]);
        let (m0, m1, m2) = (
            &mut self.m0[1..=n],
            &mut self.m1[1..=n],
            &mut self.m2[1..=n],
        );
        let (d0, d1, dd) = (
            &mut self.d0[1..=n],
            &mut self.d1[1..=n],
            &mut self.dd[1..=n],
        );
        let (mut a0, mut a1, mut a2, mut b0, mut b1, mut bb) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for q in 0..n {
            let (m, d, x) = (mask[q], values[q], q as f64);
            a0 += m;
            a1 += x * m;
            a2 += x * x * m;
            b0 += d;
            b1 += x * d;
            bb += d * d;
            m0[q] = a0;
            m1[q] = a1;
            m2[q] = a2;
            d0[q] = b0;
            d1[q] = b1;
            dd[q] = bb;
        }
    }

    /// Adds to every lag the sums of `run`, whose points meet D's local indices from `base + x` at
    /// lag slot x (slots in the order of rising index). Slot by slot, each a plain loop over
    /// contiguous slices, so it vectorises; the arithmetic per slot is that of one run and one lag.
    fn add_run(&self, run: &Run, base: usize, slots: &[f64], sums: &mut LagSums) {
        let l = slots.len();
        let (a0, b0) = (base, base + run.len);
        let (m0a, m0b) = (&self.m0[a0..a0 + l], &self.m0[b0..b0 + l]);
        let (m1a, m1b) = (&self.m1[a0..a0 + l], &self.m1[b0..b0 + l]);
        let (m2a, m2b) = (&self.m2[a0..a0 + l], &self.m2[b0..b0 + l]);
        let (d0a, d0b) = (&self.d0[a0..a0 + l], &self.d0[b0..b0 + l]);
        let (d1a, d1b) = (&self.d1[a0..a0 + l], &self.d1[b0..b0 + l]);
        let (dda, ddb) = (&self.dd[a0..a0 + l], &self.dd[b0..b0 + l]);
        let (c0, c1, af) = (run.c0, run.c1, a0 as f64);
        let LagSums {
            n,
            d,
            s,
            ds,
            dd,
            ss,
        } = sums;
        let (n, d, s, ds, dd, ss) = (
            &mut n[..l],
            &mut d[..l],
            &mut s[..l],
            &mut ds[..l],
            &mut dd[..l],
            &mut ss[..l],
        );
        for x in 0..l {
            let a = af + slots[x];
            let m0 = m0b[x] - m0a[x];
            let m1d = m1b[x] - m1a[x];
            let m1 = m1d - a * m0;
            let m2 = (m2b[x] - m2a[x]) - 2.0 * a * m1d + a * a * m0;
            let d0 = d0b[x] - d0a[x];
            let d1 = (d1b[x] - d1a[x]) - a * d0;
            n[x] += m0;
            d[x] += d0;
            s[x] += c0 * m0 + c1 * m1;
            ds[x] += c0 * d0 + c1 * d1;
            dd[x] += ddb[x] - dda[x];
            ss[x] += c0 * c0 * m0 + 2.0 * c0 * c1 * m1 + c1 * c1 * m2;
        }
    }
}

/// The sums of every lag slot, one vector per sum.
struct LagSums {
    n: Vec<f64>,
    d: Vec<f64>,
    s: Vec<f64>,
    ds: Vec<f64>,
    dd: Vec<f64>,
    ss: Vec<f64>,
}

/// The sums of every lag k in `lo..=hi`, each run (S at m) against D at m + σ·k.
fn sums_against_runs(
    runs: &[Run],
    (dt, dv): (&[f64], &[f64]),
    hf: f64,
    gap: f64,
    (lo, hi): (i64, i64),
    sigma: i64,
) -> Vec<Sums> {
    let lags = (hi - lo + 1) as usize;
    let zeros = || vec![0.0; lags];
    let mut sums = LagSums {
        n: zeros(),
        d: zeros(),
        s: zeros(),
        ds: zeros(),
        dd: zeros(),
        ss: zeros(),
    };
    // Slot x holds σ·k = kmin + x: D's index rises with the slot whichever way the lags run.
    let slots: Vec<f64> = (0..lags).map(|x| x as f64).collect();
    let (kmin, kmax) = ((sigma * lo).min(sigma * hi), (sigma * lo).max(sigma * hi));
    let block = BLOCK.max(4 * lags);
    // One block of D's grid and its prefix sums at a time, in buffers reused from block to block.
    let span = runs.last().map_or(0, |r| r.m0 + r.len as i64) - runs.first().map_or(0, |r| r.m0);
    let cap = (block + lags).min(span.max(0) as usize + lags);
    let (mut values, mut mask) = (Vec::with_capacity(cap), Vec::with_capacity(cap));
    let mut prefix = Prefix::with_capacity(cap);
    let mut i = 0;
    while i < runs.len() {
        // One block of D's grid from the first pending run's reach; every run that fits in it.
        let j0 = runs[i].m0 + kmin;
        let mut end = i;
        while end < runs.len() && runs[end].m0 + runs[end].len as i64 - 1 + kmax < j0 + block as i64
        {
            end += 1;
        }
        let end = end.max(i + 1);
        let last = &runs[end - 1];
        let len = (last.m0 + last.len as i64 - 1 + kmax - j0 + 1) as usize;
        values.resize(len, 0.0);
        mask.resize(len, 0.0);
        resample_into((dt, dv), (hf, 0.0), j0, (&mut values, &mut mask), gap);
        prefix.fill(&values, &mask);
        for run in &runs[i..end] {
            prefix.add_run(run, (run.m0 + kmin - j0) as usize, &slots, &mut sums);
        }
        i = end;
    }
    // Slot x is lag lo + x when σ = 1 and lag hi − x when σ = −1.
    let mut out: Vec<Sums> = (0..lags)
        .map(|x| Sums {
            n: sums.n[x],
            d: sums.d[x],
            s: sums.s[x],
            ds: sums.ds[x],
            dd: sums.dd[x],
            ss: sums.ss[x],
        })
        .collect();
    if sigma < 0 {
        out.reverse();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::align::grid::{grid_span, resample_on_grid};

    /// The sums on the fine grid point by point (what the fine stage computed before).
    fn direct(
        (et, ev): (&[f64], &[f64]),
        (rt, rv): (&[f64], &[f64]),
        hf: f64,
        gap: f64,
        lo: i64,
        hi: i64,
    ) -> Vec<OverlapSums> {
        let lags = (hi - lo + 1) as usize;
        let mut sums = vec![OverlapSums::default(); lags];
        let (Some((e0, e1)), Some(_)) = (
            grid_span(et[0], et[et.len() - 1], hf),
            grid_span(rt[0], rt[rt.len() - 1], hf),
        ) else {
            return sums;
        };
        let len = (e1 - e0 + 1) as usize;
        let e = resample_on_grid(et, ev, hf, e0, len, gap);
        let r = resample_on_grid(rt, rv, hf, e0 + lo, len + lags - 1, gap);
        for (l, s) in sums.iter_mut().enumerate() {
            for j in 0..len {
                let (x, mx, y, my) = (e.values[j], e.mask[j], r.values[j + l], r.mask[j + l]);
                s.n += mx * my;
                s.sa += x * my;
                s.sb += mx * y;
                s.sab += x * y;
                s.saa += x * x * my;
                s.sbb += mx * y * y;
            }
        }
        sums
    }

    /// Irregular stamps at about `rate` Hz over [t0, t0 + span] with a 3 s hole, a duplicate stamp
    /// and one stamp on the grid; values a smooth function plus a pseudo-random wiggle.
    fn signal(t0: f64, span: f64, rate: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut x = seed;
        let mut rnd = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut t, mut v) = (vec![], vec![]);
        let mut s = t0;
        while s < t0 + span {
            if !(s > t0 + 10.0 && s < t0 + 13.0) {
                t.push(s);
                v.push((0.7 * s).sin() + 0.3 * rnd());
            }
            s += (0.5 + rnd()) / rate;
        }
        let k = t.len() / 2;
        t[k + 1] = t[k];
        t[k + 2] = (t[k + 2] / 0.001).round() * 0.001;
        t.windows(2).for_each(|w| assert!(w[1] >= w[0]));
        (t, v)
    }

    fn close(a: f64, b: f64, scale: f64) -> bool {
        (a - b).abs() <= 1e-9 * scale.max(1.0)
    }

    #[test]
    fn equals_the_direct_sums_whichever_signal_is_sparse() {
        for (er, rr, lo, hi) in [
            (200.0, 10.0, -40, 40),
            (10.0, 200.0, -40, 40),
            (50.0, 50.0, 100, 160),
            (3.0, 7.0, -300, -200),
        ] {
            let (et, ev) = signal(5.0, 60.0, er, 1);
            let (rt, rv) = signal(4.3, 70.0, rr, 2);
            let fast = fine_sums((&et, &ev), (&rt, &rv), 0.001, 0.5, lo, hi);
            let slow = direct((&et, &ev), (&rt, &rv), 0.001, 0.5, lo, hi);
            assert_eq!(fast.len(), slow.len());
            assert!(
                slow.iter().any(|s| s.n > 1000.0),
                "rates {er}/{rr}: no overlap"
            );
            for (f, s) in fast.iter().zip(&slow) {
                let scale = s.n.max(s.saa).max(s.sbb);
                assert!(
                    close(f.n, s.n, scale)
                        && close(f.sa, s.sa, scale)
                        && close(f.sb, s.sb, scale)
                        && close(f.sab, s.sab, scale)
                        && close(f.saa, s.saa, scale)
                        && close(f.sbb, s.sbb, scale),
                    "rates {er}/{rr}: {f:?} vs {s:?}"
                );
            }
        }
    }
}

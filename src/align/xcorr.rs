//! Masked normalised cross-correlation (eq. 2 of the paper) for a whole range of lags, with FFTs.
//!
//! Two signals a and b on the same regular grid, each with a mask (1 where defined). For a lag k the
//! overlap is the set of j where both `mask_a[j]` and `mask_b[j + k]` are 1, and
//!
//! * raw (the paper's eq. 2 on unsigned κ): NCC(k) = Σ a·b / √(Σ a² · Σ b²) over the overlap;
//! * mean-removed (Pearson): the same after subtracting each signal's mean *over that overlap*.
//!
//! Every sum over the overlap is a correlation of two zero-padded sequences (a·mask_a against b,
//! a² against mask_b, mask_a against mask_b, …), so all lags cost a handful of FFTs (`rustfft`)
//! instead of O(N·K). [`masked_ncc_direct`] is the O(N·K) definition, used for short lag windows and
//! to test the FFT path.

use realfft::RealFftPlanner;
use rustfft::num_complex::Complex;

/// Whether the NCC subtracts each signal's mean over the overlap first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Centering {
    /// Σ a·b / √(Σ a² Σ b²): eq. (2) of the paper.
    Raw,
    /// Pearson correlation over the overlap.
    MeanRemoved,
}

/// The NCC at every lag of `lag_min..=lag_max`, where lag k pairs `a[j]` with `b[j + k]`.
#[derive(Debug, Clone, PartialEq)]
pub struct MaskedNcc {
    /// The first lag.
    pub lag_min: i64,
    /// NCC per lag, in [−1, 1]; 0 where the overlap is empty or a signal has no energy (variance)
    /// over it.
    pub ncc: Vec<f64>,
    /// Number of grid points in the overlap per lag.
    pub overlap: Vec<usize>,
}

impl MaskedNcc {
    /// The lag of entry `i`.
    pub fn lag(&self, i: usize) -> i64 {
        self.lag_min + i as i64
    }

    /// Number of lags.
    pub fn len(&self) -> usize {
        self.ncc.len()
    }

    /// True when no lag was computed.
    pub fn is_empty(&self) -> bool {
        self.ncc.is_empty()
    }
}

/// The overlap sums of one lag, from which both NCC variants follow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OverlapSums {
    /// Number of overlapping points.
    pub n: f64,
    /// Σa, Σb, Σab, Σa², Σb² over the overlap.
    pub sa: f64,
    pub sb: f64,
    pub sab: f64,
    pub saa: f64,
    pub sbb: f64,
}

impl OverlapSums {
    /// The NCC from the sums; 0 when the overlap is empty or a signal is (numerically) constant
    /// zero (raw) or constant (mean-removed) over it.
    pub fn ncc(&self, centering: Centering) -> f64 {
        if self.n < 0.5 {
            return 0.0;
        }
        let (num, va, vb) = match centering {
            Centering::Raw => (self.sab, self.saa, self.sbb),
            Centering::MeanRemoved => (
                self.sab - self.sa * self.sb / self.n,
                self.saa - self.sa * self.sa / self.n,
                self.sbb - self.sb * self.sb / self.n,
            ),
        };
        // Relative floor: FFT sums carry ~1e-12 relative error, so a variance below 1e-9 of the
        // energy is noise, not signal.
        if va <= 1e-9 * self.saa.abs().max(f64::MIN_POSITIVE)
            || vb <= 1e-9 * self.sbb.abs().max(f64::MIN_POSITIVE)
        {
            return 0.0;
        }
        (num / (va * vb).sqrt()).clamp(-1.0, 1.0)
    }
}

/// The NCC at every lag of `lag_min..=lag_max`, computed with FFTs. `a`/`mask_a` and `b`/`mask_b`
/// must have equal lengths pairwise (extra entries are ignored); values where the mask is 0 are
/// ignored. Lags outside `(-a.len(), b.len())` have an empty overlap.
pub fn masked_ncc(
    a: &[f64],
    mask_a: &[f64],
    b: &[f64],
    mask_b: &[f64],
    lag_min: i64,
    lag_max: i64,
    centering: Centering,
) -> MaskedNcc {
    let na = a.len().min(mask_a.len());
    let nb = b.len().min(mask_b.len());
    let lags = if lag_max >= lag_min {
        (lag_max - lag_min + 1) as usize
    } else {
        0
    };
    let mut out = MaskedNcc {
        lag_min,
        ncc: vec![0.0; lags],
        overlap: vec![0; lags],
    };
    if na == 0 || nb == 0 || lags == 0 {
        return out;
    }
    // Circular correlation equals the linear one at every |k| ≤ K once len ≥ max(na, nb) + K (no
    // product wraps around onto a non-zero sample); lags beyond (−na, nb) have no overlap anyway.
    let k_abs = lag_min.unsigned_abs().max(lag_max.unsigned_abs()) as usize;
    let len = (na.max(nb) + k_abs.min(na.max(nb))).next_power_of_two();
    // Real-input FFTs (`realfft`): a spectrum is len/2 + 1 bins, half a complex transform's.
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(len);
    let inv = planner.plan_fft_inverse(len);
    let spectrum = |x: &dyn Fn(usize) -> f64, n: usize| -> Vec<Complex<f64>> {
        let mut input = fwd.make_input_vec();
        for (j, v) in input.iter_mut().enumerate().take(n) {
            *v = x(j);
        }
        let mut out = fwd.make_output_vec();
        // Lengths come from the planner's own buffers: the transform cannot fail.
        fwd.process(&mut input, &mut out)
            .expect("realfft buffers of the planned length");
        out
    };
    let ma = |j: usize| if mask_a[j] > 0.5 { 1.0 } else { 0.0 };
    let mb = |j: usize| if mask_b[j] > 0.5 { 1.0 } else { 0.0 };
    let av = |j: usize| if mask_a[j] > 0.5 { a[j] } else { 0.0 };
    let bv = |j: usize| if mask_b[j] > 0.5 { b[j] } else { 0.0 };
    // Correlation c[k] = Σ_j x[j]·y[j+k] = IFFT(conj(X)·Y)[k mod len], real. Only the searched lags
    // are kept, and each spectrum is dropped once no correlation needs it (a coarse search of a
    // 2-hour mission holds four spectra of four megabytes each).
    let corr = |x: &[Complex<f64>], y: &[Complex<f64>]| -> Vec<f64> {
        let mut prod: Vec<Complex<f64>> = x.iter().zip(y).map(|(x, y)| x.conj() * y).collect();
        // Real signals: the DC and Nyquist bins are real (their rounding residue is dropped).
        let last = prod.len() - 1;
        prod[0].im = 0.0;
        prod[last].im = 0.0;
        let mut out = inv.make_output_vec();
        inv.process(&mut prod, &mut out)
            .expect("realfft buffers of the planned length");
        let scale = 1.0 / len as f64;
        (0..lags)
            .map(|i| out[(lag_min + i as i64).rem_euclid(len as i64) as usize] * scale)
            .collect()
    };
    let (f_a, f_ma) = (spectrum(&av, na), spectrum(&ma, na));
    let (f_b, f_mb) = (spectrum(&bv, nb), spectrum(&mb, nb));
    let sab = corr(&f_a, &f_b);
    let count = corr(&f_ma, &f_mb);
    let sa_sb = match centering {
        Centering::MeanRemoved => Some((corr(&f_a, &f_mb), corr(&f_ma, &f_b))),
        Centering::Raw => None,
    };
    drop((f_a, f_b));
    let saa = corr(&spectrum(&|j| av(j) * av(j), na), &f_mb);
    let sbb = corr(&f_ma, &spectrum(&|j| bv(j) * bv(j), nb));
    for i in 0..lags {
        let k = lag_min + i as i64;
        if k <= -(na as i64) || k >= nb as i64 {
            continue;
        }
        let n = count[i].round().max(0.0);
        let (sa, sb) = sa_sb.as_ref().map_or((0.0, 0.0), |(a, b)| (a[i], b[i]));
        let sums = OverlapSums {
            n,
            sa,
            sb,
            sab: sab[i],
            saa: saa[i].max(0.0),
            sbb: sbb[i].max(0.0),
        };
        out.overlap[i] = n as usize;
        out.ncc[i] = sums.ncc(centering);
    }
    out
}

/// The overlap sums of `a[j]` and `b[j + lag]` by direct summation.
pub fn overlap_sums(a: &[f64], mask_a: &[f64], b: &[f64], mask_b: &[f64], lag: i64) -> OverlapSums {
    let na = a.len().min(mask_a.len()) as i64;
    let nb = b.len().min(mask_b.len()) as i64;
    let mut s = OverlapSums::default();
    let j0 = (-lag).max(0);
    let j1 = na.min(nb - lag);
    for j in j0..j1 {
        let (ja, jb) = (j as usize, (j + lag) as usize);
        if mask_a[ja] > 0.5 && mask_b[jb] > 0.5 {
            let (x, y) = (a[ja], b[jb]);
            s.n += 1.0;
            s.sa += x;
            s.sb += y;
            s.sab += x * y;
            s.saa += x * x;
            s.sbb += y * y;
        }
    }
    s
}

/// The same as [`masked_ncc`] by direct O(N·K) summation: cheaper for a few lags, and the
/// definition the FFT path is tested against.
pub fn masked_ncc_direct(
    a: &[f64],
    mask_a: &[f64],
    b: &[f64],
    mask_b: &[f64],
    lag_min: i64,
    lag_max: i64,
    centering: Centering,
) -> MaskedNcc {
    let mut out = MaskedNcc {
        lag_min,
        ncc: vec![],
        overlap: vec![],
    };
    for k in lag_min..=lag_max {
        let s = overlap_sums(a, mask_a, b, mask_b, k);
        out.ncc.push(s.ncc(centering));
        out.overlap.push(s.n as usize);
    }
    out
}

//! Masked normalised cross-correlation (eq. 2 of the paper) for a whole range of lags, with FFTs.
//!
//! Two signals a and b on the same regular grid, each with a mask (1 where defined). For a lag k the
//! overlap is the set of j where both `mask_a[j]` and `mask_b[j + k]` are 1, and
//!
//! * raw (the paper's eq. 2 on unsigned κ): NCC(k) = Σ a·b / √(Σ a² · Σ b²) over the overlap;
//! * mean-removed (Pearson): the same after subtracting each signal's mean *over that overlap*.
//!
//! Every sum over the overlap is a correlation of two zero-padded sequences (a·mask_a against b,
//! a² against mask_b, mask_a against mask_b, …), so all lags cost a handful of FFTs (`realfft`, on
//! `rustfft`) instead of O(N·K). The correlation runs block by block (overlap-add): a block of a
//! against the stretch of b its lags reach, with FFTs of about four times the lags. On a 2-hour
//! mission the coarse search's ±30 s are 3001 lags over 360,000 grid points: one transform over the
//! whole grid takes 2¹⁹-point buffers (4 MB a spectrum, several at once), the blocks 2¹⁴-point ones,
//! and read the grid as they go ([`crate::align::grid::GridBlocks`]). [`masked_ncc_direct`] is the O(N·K) definition, used for
//! short lag windows and to test the FFT path.

use realfft::RealFftPlanner;

use crate::align::grid::{GridBlocks, MaskedSlices};
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
    let a = MaskedSlices {
        values: a,
        mask: mask_a,
    };
    let b = MaskedSlices {
        values: b,
        mask: mask_b,
    };
    masked_ncc_blocks(&a, &b, lag_min, lag_max, centering)
}

/// [`masked_ncc`] of two signals read a block at a time (overlap-add): `a` is cut into blocks, each
/// correlated by FFT with the stretch of `b` its lags reach. Memory is a few FFT buffers of about
/// four times the number of lags, whatever the signals' length, and the work is that of one FFT over
/// the whole signal.
pub fn masked_ncc_blocks(
    a: &impl GridBlocks,
    b: &impl GridBlocks,
    lag_min: i64,
    lag_max: i64,
    centering: Centering,
) -> MaskedNcc {
    let (na, nb) = (a.len() as i64, b.len() as i64);
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
    // Only lags in (−na, nb) have an overlap.
    let (k0, k1) = (lag_min.max(1 - na), lag_max.min(nb - 1));
    if na == 0 || nb == 0 || k1 < k0 {
        return out;
    }
    let sums = BlockCorrelator::new((k1 - k0 + 1) as usize, na as usize, centering).run(a, b, k0);
    for (j, s) in sums.iter().enumerate() {
        let i = (k0 - lag_min) as usize + j;
        out.overlap[i] = s.n as usize;
        out.ncc[i] = s.ncc(centering);
    }
    out
}

/// The FFT plans and buffers of a blocked correlation: blocks of `block` points of a against
/// stretches of `len` = `block` + lags − 1 points of b (a circular correlation of length `len` then
/// equals the linear one at every searched lag).
struct BlockCorrelator {
    lags: usize,
    block: usize,
    len: usize,
    centering: Centering,
    fwd: std::sync::Arc<dyn realfft::RealToComplex<f64>>,
    inv: std::sync::Arc<dyn realfft::ComplexToReal<f64>>,
}

/// The smallest FFT length of a blocked correlation (below it, per-block overheads dominate).
const MIN_BLOCK_FFT: usize = 1024;

impl BlockCorrelator {
    fn new(lags: usize, na: usize, centering: Centering) -> Self {
        // About four times the lags: three quarters of each transform is new signal, and a short
        // signal gets one transform of its own length.
        let len = (4 * lags)
            .next_power_of_two()
            .max(MIN_BLOCK_FFT)
            .min((na + lags - 1).next_power_of_two());
        let mut planner = RealFftPlanner::<f64>::new();
        BlockCorrelator {
            lags,
            block: len + 1 - lags,
            len,
            centering,
            fwd: planner.plan_fft_forward(len),
            inv: planner.plan_fft_inverse(len),
        }
    }

    /// The overlap sums at lags `k0`, `k0 + 1`, … (`lags` of them), block by block.
    fn run(&self, a: &impl GridBlocks, b: &impl GridBlocks, k0: i64) -> Vec<OverlapSums> {
        let mut acc = vec![OverlapSums::default(); self.lags];
        let (mut av, mut am) = (vec![0.0; self.block], vec![0.0; self.block]);
        let (mut bv, mut bm) = (vec![0.0; self.len], vec![0.0; self.len]);
        for start in (0..a.len()).step_by(self.block) {
            let n = self.block.min(a.len() - start);
            a.read(start as i64, &mut av[..n], &mut am[..n]);
            if am[..n].iter().all(|&m| m < 0.5) {
                continue;
            }
            b.read(start as i64 + k0, &mut bv, &mut bm);
            if bm.iter().all(|&m| m < 0.5) {
                continue;
            }
            self.add_block((&av[..n], &am[..n]), (&bv, &bm), &mut acc);
        }
        for s in &mut acc {
            s.n = s.n.round().max(0.0);
            s.saa = s.saa.max(0.0);
            s.sbb = s.sbb.max(0.0);
        }
        acc
    }

    /// Adds one block's sums: `c[k] = Σ_i x[i]·y[i + k] = IFFT(conj(X)·Y)[k]` for every product.
    fn add_block(
        &self,
        (av, am): (&[f64], &[f64]),
        (bv, bm): (&[f64], &[f64]),
        acc: &mut [OverlapSums],
    ) {
        let squares = |v: &[f64]| v.iter().map(|x| x * x).collect::<Vec<f64>>();
        let (fa, fma, faa) = (
            self.spectrum(av),
            self.spectrum(am),
            self.spectrum(&squares(av)),
        );
        let (fb, fmb, fbb) = (
            self.spectrum(bv),
            self.spectrum(bm),
            self.spectrum(&squares(bv)),
        );
        let mut add =
            |x: &[Complex<f64>], y: &[Complex<f64>], field: fn(&mut OverlapSums) -> &mut f64| {
                let c = self.correlate(x, y);
                for (s, v) in acc.iter_mut().zip(c) {
                    *field(s) += v;
                }
            };
        add(&fa, &fb, |s| &mut s.sab);
        add(&fma, &fmb, |s| &mut s.n);
        add(&faa, &fmb, |s| &mut s.saa);
        add(&fma, &fbb, |s| &mut s.sbb);
        if self.centering == Centering::MeanRemoved {
            add(&fa, &fmb, |s| &mut s.sa);
            add(&fma, &fb, |s| &mut s.sb);
        }
    }

    /// The real FFT of `x` zero-padded to the transform's length.
    fn spectrum(&self, x: &[f64]) -> Vec<Complex<f64>> {
        let mut input = self.fwd.make_input_vec();
        input[..x.len()].copy_from_slice(x);
        let mut out = self.fwd.make_output_vec();
        // Lengths come from the planner's own buffers: the transform cannot fail.
        self.fwd
            .process(&mut input, &mut out)
            .expect("realfft buffers of the planned length");
        out
    }

    /// The first `lags` entries of the circular correlation of two spectra.
    fn correlate(&self, x: &[Complex<f64>], y: &[Complex<f64>]) -> Vec<f64> {
        let mut prod: Vec<Complex<f64>> = x.iter().zip(y).map(|(x, y)| x.conj() * y).collect();
        // Real signals: the DC and Nyquist bins are real (their rounding residue is dropped).
        let last = prod.len() - 1;
        prod[0].im = 0.0;
        prod[last].im = 0.0;
        let mut out = self.inv.make_output_vec();
        self.inv
            .process(&mut prod, &mut out)
            .expect("realfft buffers of the planned length");
        let scale = 1.0 / self.len as f64;
        out.truncate(self.lags);
        out.iter_mut().for_each(|v| *v *= scale);
        out
    }
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

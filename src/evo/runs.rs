//! What evo_res lacks and its users ask for: a statistic over repeated runs of one estimator (mean and
//! 95 % interval), and a paired comparison of two estimators on the same missions that names the
//! better one only when the difference is larger than the run-to-run scatter.
//!
//! The interval is Student's t: mean ± t(0.975, n−1)·s/√n, s the sample standard deviation of the
//! runs' values. The comparison works on the relative difference r = (B − A)/A of the two estimators'
//! run means on each mission. With two or more missions it is a paired t interval over the missions'
//! r (the scatter between missions contains the run-to-run scatter); with one mission, Welch's interval
//! from the two sets of runs. B is called better (worse) only when the whole 95 % interval of r lies
//! below (above) zero.

use statrs::distribution::{ContinuousCDF, StudentsT};

/// Mean and half-width of its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    pub mean: f64,
    pub half_width: f64,
    pub n: usize,
}

/// The 0.975 quantile of Student's t with `df` degrees of freedom.
pub fn t975(df: f64) -> f64 {
    StudentsT::new(0.0, 1.0, df.max(1e-3)).map_or(f64::NAN, |t| t.inverse_cdf(0.975))
}

/// The sample (n − 1) variance.
fn variance(v: &[f64], mean: f64) -> f64 {
    v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() as f64 - 1.0)
}

/// Mean ± 95 % interval of `v` (at least two values).
pub fn mean_interval(v: &[f64]) -> Option<Interval> {
    if v.len() < 2 || v.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let se = (variance(v, mean) / n).sqrt();
    Some(Interval {
        mean,
        half_width: t975(n - 1.0) * se,
        n: v.len(),
    })
}

/// The outcome of a comparison.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// B's values are lower (better): the whole interval of (B − A)/A is below zero.
    BBetter,
    /// B's values are higher (worse).
    BWorse,
    /// The interval contains zero: the difference is within the scatter.
    NoDifference,
    /// Not enough runs or missions to say (one mission and fewer than two runs of each).
    Undecided,
}

/// One mission of a comparison: both estimators' run values.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionPair {
    pub mission: String,
    pub a: Vec<f64>,
    pub b: Vec<f64>,
}

/// A comparison's result: the mean relative difference (B − A)/A with its 95 % half-width, how it was
/// computed and the verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    pub relative: f64,
    pub half_width: f64,
    /// `paired over N missions` or `Welch over the runs of one mission`.
    pub method: String,
    pub verdict: Verdict,
    /// Per mission: (mission, A's run mean, B's, relative difference, its Welch half-width if both
    /// have two runs or more).
    pub missions: Vec<(String, f64, f64, f64, Option<f64>)>,
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Welch's half-width of mean(b) − mean(a), or `None` with fewer than two runs on a side.
fn welch(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.len() < 2 || b.len() < 2 {
        return None;
    }
    let (va, vb) = (
        variance(a, mean(a)) / a.len() as f64,
        variance(b, mean(b)) / b.len() as f64,
    );
    let se2 = va + vb;
    if se2 == 0.0 {
        return Some(0.0);
    }
    let df = se2 * se2
        / (va * va / (a.len() as f64 - 1.0) + vb * vb / (b.len() as f64 - 1.0)).max(1e-300);
    Some(t975(df) * se2.sqrt())
}

/// Compares B against A on `missions` (each with at least one run of each).
pub fn compare(missions: &[MissionPair]) -> Comparison {
    let rows: Vec<(String, f64, f64, f64, Option<f64>)> = missions
        .iter()
        .filter(|m| !m.a.is_empty() && !m.b.is_empty())
        .map(|m| {
            let (ma, mb) = (mean(&m.a), mean(&m.b));
            (
                m.mission.clone(),
                ma,
                mb,
                (mb - ma) / ma,
                welch(&m.a, &m.b).map(|h| h / ma),
            )
        })
        .collect();
    let verdict_of = |r: f64, h: f64| {
        if !h.is_finite() {
            Verdict::Undecided
        } else if r + h < 0.0 {
            Verdict::BBetter
        } else if r - h > 0.0 {
            Verdict::BWorse
        } else {
            Verdict::NoDifference
        }
    };
    let (relative, half_width, method) = match rows.len() {
        0 => (
            f64::NAN,
            f64::NAN,
            "no mission with runs of both".to_string(),
        ),
        1 => (
            rows[0].3,
            rows[0].4.unwrap_or(f64::NAN),
            "Welch over the runs of one mission".to_string(),
        ),
        n => {
            let r: Vec<f64> = rows.iter().map(|x| x.3).collect();
            let i = mean_interval(&r).expect("two missions or more");
            (i.mean, i.half_width, format!("paired over {n} missions"))
        }
    };
    Comparison {
        relative,
        half_width,
        method,
        verdict: verdict_of(relative, half_width),
        missions: rows,
    }
}

/// The estimator a result file belongs to for `--runs`/`--compare`: its file name without the
/// extension and a trailing run number (`orb_03.zip`, `orb-run3.zip` → `orb`, `orb-run`).
pub fn estimator_of(path: &std::path::Path) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let t = stem
        .trim_end_matches(|c: char| c.is_ascii_digit())
        .trim_end_matches(['_', '-', '.', ' ']);
    if t.is_empty() {
        stem
    } else {
        t.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_interval_of_four_runs() {
        let m = mean_interval(&[1.0, 1.1, 0.9, 1.0]).unwrap();
        assert!((m.mean - 1.0).abs() < 1e-12 && m.half_width > 0.1 && m.half_width < 0.2);
    }

    #[test]
    fn estimator_of_drops_the_run_number() {
        assert_eq!(estimator_of(std::path::Path::new("res/orb_03.zip")), "orb");
        assert_eq!(estimator_of(std::path::Path::new("vins.zip")), "vins");
        assert_eq!(estimator_of(std::path::Path::new("12.zip")), "12");
    }
    use rand::{Rng, SeedableRng};

    #[test]
    fn t_quantiles_are_the_tables() {
        assert!((t975(1.0) - 12.706).abs() < 1e-3);
        assert!((t975(9.0) - 2.262).abs() < 1e-3);
        assert!((t975(1e6) - 1.960).abs() < 1e-3);
    }

    /// The interval covers the true mean about 95 % of the time (2000 seeded experiments of 10 runs).
    #[test]
    fn interval_covers_95_percent() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut hits = 0;
        for _ in 0..2000 {
            let v: Vec<f64> = (0..10)
                .map(|_| 1.0 + 0.1 * (rng.random::<f64>() - 0.5))
                .collect();
            let i = mean_interval(&v).unwrap();
            if (i.mean - 1.0).abs() <= i.half_width {
                hits += 1;
            }
        }
        assert!((1840..=1960).contains(&hits), "{hits}");
    }

    #[test]
    fn one_mission_uses_welch() {
        let a = vec![1.0, 1.01, 0.99, 1.0, 1.02];
        let same = compare(&[MissionPair {
            mission: "m".into(),
            a: a.clone(),
            b: vec![1.0, 0.99, 1.01, 1.02, 1.0],
        }]);
        assert_eq!(same.verdict, Verdict::NoDifference);
        let worse = compare(&[MissionPair {
            mission: "m".into(),
            a: a.clone(),
            b: a.iter().map(|x| x * 1.1).collect(),
        }]);
        assert_eq!(worse.verdict, Verdict::BWorse);
        assert!((worse.relative - 0.1).abs() < 1e-9);
        let once = compare(&[MissionPair {
            mission: "m".into(),
            a: vec![1.0],
            b: vec![2.0],
        }]);
        assert_eq!(once.verdict, Verdict::Undecided);
    }
}

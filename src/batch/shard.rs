//! `--shard I/N` and `--shard auto`: a deterministic subset of a batch, so that N independent jobs (a
//! Slurm job array, a Kubernetes Indexed Job, any scheduler) cover every mission exactly once;
//! `trajdrift merge` then builds the summary.
//!
//! Missions are ordered by name and shard I keeps those at positions p with p mod N = I − 1: the split
//! depends only on the names, not on the manifest's order or the machine. `auto` reads the scheduler's
//! variables, which count from 0 (Slurm from the array's first index), where `--shard` counts from 1.

use crate::error::{Error, Result};

/// Shard I of N (1-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = Error;

    /// Parses `I/N` with 1 ≤ I ≤ N.
    fn from_str(s: &str) -> Result<Shard> {
        let bad =
            || Error::InvalidArgument(format!("--shard {s}: expected I/N with 1 ≤ I ≤ N, or auto"));
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse::<usize>().map_err(|_| bad())?,
            n.trim().parse::<usize>().map_err(|_| bad())?,
        );
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// The environment variable that gives the shard count to a Kubernetes Indexed Job (or any scheduler
/// that only gives an index) when `--shards` is not passed.
pub const SHARDS_VAR: &str = "TRAJDRIFT_SHARDS";

impl Shard {
    /// The shard named by `--shard` (`I/N` or `auto`); `shards` is `--shards N`; `env` looks up an
    /// environment variable (a parameter so that tests need not touch the process environment).
    pub fn resolve(
        spec: &str,
        shards: Option<usize>,
        env: &dyn Fn(&str) -> Option<String>,
    ) -> Result<Shard> {
        if spec.trim() != "auto" {
            let s: Shard = spec.parse()?;
            return match shards {
                Some(n) if n != s.count => Err(Error::InvalidArgument(format!(
                    "--shard {spec} and --shards {n} disagree on the shard count"
                ))),
                _ => Ok(s),
            };
        }
        if env("SLURM_ARRAY_TASK_ID").is_some() {
            return Shard::from_slurm(shards, env);
        }
        if env("JOB_COMPLETION_INDEX").is_some() {
            return Shard::from_kubernetes(shards, env);
        }
        Err(Error::InvalidArgument(
            "--shard auto: neither SLURM_ARRAY_TASK_ID (a Slurm job array) nor JOB_COMPLETION_INDEX \
             (a Kubernetes Indexed Job) is set; pass --shard I/N"
                .into(),
        ))
    }

    /// A Slurm job array: task `ID` of `COUNT` tasks numbered from `MIN` to `MAX` in steps of `STEP`;
    /// the shard is the task's rank in the array. An array given as a list of indices
    /// (`--array=1,3,7`) is not an evenly spaced range: its ranks cannot be known from these variables,
    /// so it is refused rather than mapped wrongly (1 and 7 would run as shards 1 and 3, and shard 2
    /// never).
    fn from_slurm(shards: Option<usize>, env: &dyn Fn(&str) -> Option<String>) -> Result<Shard> {
        let id = env_number(env, "SLURM_ARRAY_TASK_ID")?.unwrap_or(0);
        let min = env_number(env, "SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let max = env_number(env, "SLURM_ARRAY_TASK_MAX")?;
        let step_var = env_number(env, "SLURM_ARRAY_TASK_STEP")?;
        let count = match (env_number(env, "SLURM_ARRAY_TASK_COUNT")?, shards) {
            (Some(c), Some(n)) if c != n => {
                return Err(Error::InvalidArgument(format!(
                    "--shards {n} disagrees with SLURM_ARRAY_TASK_COUNT={c}; drop --shards or resize the array"
                )))
            }
            (Some(c), _) | (None, Some(c)) => c,
            (None, None) => {
                return Err(Error::InvalidArgument(
                    "--shard auto: SLURM_ARRAY_TASK_COUNT is not set (Slurm sets it for job arrays); pass --shards N"
                        .into(),
                ))
            }
        };
        let list = |why: &str| {
            Error::InvalidArgument(format!(
                "--shard auto: the Slurm array (SLURM_ARRAY_TASK_MIN={min}, MAX={}, COUNT={count}, STEP={}) {why}: a list of indices such as --array=1,3,7 cannot be mapped onto shards; submit an evenly spaced range (--array=0-{}) or pass --shard I/N",
                max.map_or("unset".into(), |m| m.to_string()),
                step_var.map_or("unset".into(), |s| s.to_string()),
                count.saturating_sub(1)
            ))
        };
        let step = match (step_var, max) {
            (Some(s), _) if s > 0 => s,
            (Some(_), _) => return Err(list("has a step of 0")),
            // No step given: the one an evenly spaced range from MIN to MAX would have.
            (None, Some(max)) if count > 1 => {
                let span = max
                    .checked_sub(min)
                    .ok_or_else(|| list("ends before it starts"))?;
                if span % (count - 1) != 0 {
                    return Err(list("is not evenly spaced"));
                }
                (span / (count - 1)).max(1)
            }
            (None, _) => 1,
        };
        if let Some(max) = max {
            let last = min.checked_add(step.saturating_mul(count.saturating_sub(1)));
            if count == 0 || last != Some(max) {
                return Err(list("is not the evenly spaced range MIN, MIN+STEP, …, MAX"));
            }
        }
        if id < min || (id - min) % step != 0 {
            return Err(Error::InvalidArgument(format!(
                "--shard auto: SLURM_ARRAY_TASK_ID={id} is not in the array {min}, {min}+{step}, …"
            )));
        }
        Shard::checked((id - min) / step, count, "SLURM_ARRAY_TASK_ID")
    }

    /// A Kubernetes Indexed Job: `JOB_COMPLETION_INDEX` from 0, the count from `--shards` or
    /// [`SHARDS_VAR`] (the Job's `completions`).
    fn from_kubernetes(
        shards: Option<usize>,
        env: &dyn Fn(&str) -> Option<String>,
    ) -> Result<Shard> {
        let index = env_number(env, "JOB_COMPLETION_INDEX")?.unwrap_or(0);
        let count = match shards {
            Some(n) => n,
            None => env_number(env, SHARDS_VAR)?.ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "--shard auto: JOB_COMPLETION_INDEX is set but not the shard count; pass --shards N or set {SHARDS_VAR} to the Job's completions"
                ))
            })?,
        };
        Shard::checked(index, count, "JOB_COMPLETION_INDEX")
    }

    /// Shard `zero_based + 1` of `count`, refused when outside 1..=count.
    fn checked(zero_based: usize, count: usize, var: &str) -> Result<Shard> {
        if count == 0 || zero_based >= count {
            return Err(Error::InvalidArgument(format!(
                "--shard auto: {var} gives shard {} of {count}; the shard count must exceed the index",
                zero_based + 1
            )));
        }
        Ok(Shard {
            index: zero_based + 1,
            count,
        })
    }

    /// Which of `names` this shard runs: a mask in the order of `names`.
    pub fn select(&self, names: &[&str]) -> Vec<bool> {
        let mut order: Vec<usize> = (0..names.len()).collect();
        order.sort_by(|&a, &b| names[a].cmp(names[b]));
        let mut keep = vec![false; names.len()];
        for (pos, &i) in order.iter().enumerate() {
            keep[i] = pos % self.count == self.index - 1;
        }
        keep
    }

    /// The stem of this shard's own summary files, so that shards sharing one output folder do not
    /// overwrite each other's summary (`trajdrift merge` writes the `summary.*` of the whole run).
    pub fn summary_stem(&self) -> String {
        format!("summary-shard-{}-of-{}", self.index, self.count)
    }
}

fn env_number(env: &dyn Fn(&str) -> Option<String>, var: &str) -> Result<Option<usize>> {
    env(var)
        .map(|v| {
            v.trim().parse::<usize>().map_err(|_| {
                Error::InvalidArgument(format!(
                    "--shard auto: {var}={v:?} is not a non-negative integer"
                ))
            })
        })
        .transpose()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn shards_partition_the_missions(n in 1usize..6, names in proptest::collection::btree_set("[a-z]{1,6}", 0..30)) {
            let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
            let mut covered = vec![0; names.len()];
            for i in 1..=n {
                let s: Shard = format!("{i}/{n}").parse().unwrap();
                for (k, keep) in s.select(&names).into_iter().enumerate() {
                    covered[k] += usize::from(keep);
                }
            }
            prop_assert!(covered.iter().all(|&c| c == 1));
        }
    }

    #[test]
    fn parse() {
        assert_eq!(
            "2/3".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 3 }
        );
        assert!("0/3".parse::<Shard>().is_err());
        assert!("4/3".parse::<Shard>().is_err());
        assert!("x".parse::<Shard>().is_err());
    }

    fn vars(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let pairs: Vec<(String, String)> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |k| pairs.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone())
    }

    #[test]
    fn slurm_arrays_count_from_their_first_index() {
        let env = vars(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        let s = Shard::resolve("auto", None, &env).unwrap();
        assert_eq!(s, Shard { index: 2, count: 3 });
        let stepped = vars(&[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        let s = Shard::resolve("auto", None, &stepped).unwrap();
        assert_eq!(s, Shard { index: 3, count: 3 });
        assert!(Shard::resolve("auto", Some(4), &env).is_err());
    }

    #[test]
    fn slurm_list_arrays_are_refused_and_ranges_mapped_by_rank() {
        let task = |id: &str, min: &str, max: &str, count: &str, step: Option<&str>| {
            let mut v = vec![
                ("SLURM_ARRAY_TASK_ID", id),
                ("SLURM_ARRAY_TASK_MIN", min),
                ("SLURM_ARRAY_TASK_MAX", max),
                ("SLURM_ARRAY_TASK_COUNT", count),
            ];
            if let Some(s) = step {
                v.push(("SLURM_ARRAY_TASK_STEP", s));
            }
            Shard::resolve("auto", None, &vars(&v))
        };
        // --array=1,3,7: never shards 1 and 3 of 3 with 2 missing.
        for id in ["1", "3", "7"] {
            for step in [Some("1"), None, Some("3")] {
                let r = task(id, "1", "7", "3", step);
                if let Ok(s) = r {
                    // Only the evenly spaced reading 1, 4, 7 (step 3, given or implied by MIN, MAX and
                    // COUNT) maps, and 3 is not in it: that task is refused, never run as another.
                    assert_ne!(step, Some("1"), "{id}: {s:?}");
                    assert!(id != "3");
                }
            }
            let e = task(id, "1", "7", "3", Some("1")).unwrap_err().to_string();
            assert!(
                e.contains("--array=1,3,7") && e.contains("--shard I/N"),
                "{e}"
            );
        }
        // --array=2-10:4 (2, 6, 10): ranks 0, 1, 2.
        for (id, index) in [("2", 1), ("6", 2), ("10", 3)] {
            assert_eq!(
                task(id, "2", "10", "3", Some("4")).unwrap(),
                Shard { index, count: 3 }
            );
            assert_eq!(
                task(id, "2", "10", "3", None).unwrap(),
                Shard { index, count: 3 }
            );
        }
        assert!(task("5", "5", "5", "1", Some("1")).is_ok());
    }

    #[test]
    fn kubernetes_needs_a_count() {
        let env = vars(&[("JOB_COMPLETION_INDEX", "0")]);
        assert!(Shard::resolve("auto", None, &env).is_err());
        let s = Shard::resolve("auto", Some(2), &env).unwrap();
        assert_eq!(s, Shard { index: 1, count: 2 });
        let env = vars(&[("JOB_COMPLETION_INDEX", "1"), (SHARDS_VAR, "2")]);
        let s = Shard::resolve("auto", None, &env).unwrap();
        assert_eq!(s, Shard { index: 2, count: 2 });
        let env = vars(&[("JOB_COMPLETION_INDEX", "2"), (SHARDS_VAR, "2")]);
        assert!(Shard::resolve("auto", None, &env).is_err());
    }

    #[test]
    fn auto_without_a_scheduler_is_a_usage_error() {
        let err = Shard::resolve("auto", None, &vars(&[])).unwrap_err();
        assert!(err.to_string().contains("--shard I/N"), "{err}");
    }
}

//! `--shard I/N`: a deterministic subset of a manifest, so that N independent jobs (a Slurm array, any
//! cluster scheduler) cover every mission exactly once; `trajdrift merge` then builds the summary.
//!
//! Missions are ordered by name and shard I keeps those at positions p with p mod N = I − 1: the split
//! depends only on the names, not on the manifest's order or the machine.

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
        let bad = || Error::InvalidArgument(format!("--shard {s}: expected I/N with 1 ≤ I ≤ N"));
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

impl Shard {
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
}

//! What `trajdrift topics` says about TF: the frame pairs `/tf` and `/tf_static` carry, and the
//! `/tf:PARENT:CHILD` names a user can pass.
//!
//! A recording's index lists channels, not frames, so this takes one pass over the TF channels only
//! (every other channel is skipped unread). Memory follows the number of distinct pairs.

use std::collections::{BTreeMap, HashMap};

use crate::error::Result;
use crate::sources::recording::Recording;
use crate::sources::tf_chain::{decode_edges, frame_name, is_static_channel, is_tf_channel};
use crate::sources::{Progress, TopicInfo};

/// One parent → child pair of the TF tree, as a channel carries it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct FramePair {
    /// `/tf` or `/tf_static`, as the recording spells it.
    pub topic: String,
    /// Frame names without a leading `/`.
    pub parent: String,
    pub child: String,
    /// True on `/tf_static`.
    pub is_static: bool,
    /// Edges read (transforms, not messages).
    pub count: u64,
    /// The name to pass as a topic for this edge alone, e.g. `/tf:odom:base_link`.
    pub chain: String,
}

/// The chain topic name for `parent` → `child`.
pub fn chain_topic(parent: &str, child: &str) -> String {
    format!("/tf:{parent}:{child}")
}

/// Every frame pair of `rec`'s TF channels, sorted by topic, parent, child.
pub fn frame_pairs(rec: &dyn Recording, progress: Progress<'_>) -> Result<Vec<FramePair>> {
    scan(rec, progress).map(|(pairs, _)| pairs)
}

/// [`frame_pairs`], and where the recording was cut short when it was (the pass reads every record).
pub fn scan(rec: &dyn Recording, progress: Progress<'_>) -> Result<(Vec<FramePair>, Option<u64>)> {
    let path = rec.path().to_path_buf();
    let mut counts: BTreeMap<(String, String, String), (bool, u64)> = BTreeMap::new();
    let mut index: HashMap<u16, u64> = HashMap::new();
    let outcome = rec.pass(&mut |c| is_tf_channel(c), progress, &mut |c, m| {
        let i = index.entry(c.id).or_default();
        let edges = decode_edges(&path, c, *i, m.data)?;
        *i += 1;
        for e in edges {
            let key = (
                c.topic.clone(),
                frame_name(&e.parent).to_string(),
                frame_name(&e.child).to_string(),
            );
            counts.entry(key).or_insert((is_static_channel(c), 0)).1 += 1;
        }
        Ok(())
    })?;
    let pairs = counts
        .into_iter()
        .map(|((topic, parent, child), (is_static, count))| FramePair {
            chain: chain_topic(&parent, &child),
            topic,
            parent,
            child,
            is_static,
            count,
        })
        .collect();
    Ok((pairs, outcome.truncated_at))
}

/// The root → leaf chains of the tree `pairs` form that cross at least one `/tf` edge (a chain of
/// static edges only has no trajectory), as topic names, sorted. With several parents for one child
/// (bad data) the first listed wins.
pub fn root_leaf_chains(pairs: &[FramePair]) -> Vec<String> {
    let mut parent_of: HashMap<&str, (&str, bool)> = HashMap::new();
    for p in pairs {
        parent_of
            .entry(p.child.as_str())
            .and_modify(|e| {
                if e.0 == p.parent && !p.is_static {
                    e.1 = true;
                }
            })
            .or_insert((p.parent.as_str(), !p.is_static));
    }
    let is_parent: std::collections::HashSet<&str> = parent_of.values().map(|(p, _)| *p).collect();
    let mut out: Vec<String> = parent_of
        .keys()
        .filter(|leaf| !is_parent.contains(*leaf))
        .filter_map(|leaf| {
            let mut f = *leaf;
            let mut dynamic = false;
            for _ in 0..=parent_of.len() {
                match parent_of.get(f) {
                    Some((p, d)) => {
                        dynamic |= d;
                        f = p;
                    }
                    None => break,
                }
            }
            dynamic.then(|| chain_topic(f, leaf))
        })
        .collect();
    out.sort();
    out
}

/// Puts `pairs` on the rows of the channels that carry them, and the root → leaf chains on the first
/// `/tf` (dynamic) row.
pub fn attach(topics: &mut [TopicInfo], pairs: &[FramePair]) {
    let chains = root_leaf_chains(pairs);
    let mut chains_placed = false;
    for t in topics.iter_mut() {
        t.frame_pairs = pairs
            .iter()
            .filter(|p| p.topic == t.topic)
            .cloned()
            .collect();
        if !chains_placed && !t.frame_pairs.is_empty() && frame_name(&t.topic) == "tf" {
            t.tf_chains = chains.clone();
            chains_placed = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(parent: &str, child: &str, is_static: bool) -> FramePair {
        FramePair {
            topic: if is_static { "/tf_static" } else { "/tf" }.into(),
            parent: parent.into(),
            child: child.into(),
            is_static,
            count: 1,
            chain: chain_topic(parent, child),
        }
    }

    #[test]
    fn leaves_are_reached_from_the_root() {
        let pairs = [
            pair("map", "odom", false),
            pair("odom", "base_link", false),
            pair("base_link", "base_footprint", true),
            pair("base_link", "wheel", false),
            pair("world", "fixed", true),
        ];
        assert_eq!(
            root_leaf_chains(&pairs),
            vec!["/tf:map:base_footprint", "/tf:map:wheel"]
        );
    }
}

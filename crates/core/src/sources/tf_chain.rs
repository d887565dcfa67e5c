//! TF chains without a ROS install: the `/tf:PARENT:CHILD` topics and `tf-static:` levers.
//!
//! A topic named `/tf:PARENT:CHILD` is not a channel: it is the pose of `CHILD` in `PARENT` composed
//! from the `/tf` and `/tf_static` edges between them (e.g. map→odom→base_link). The edges are
//! collected by [`TfCollector`] during the same single pass that reads the other requested topics
//! (`crate::sources::extract`), so MCAP files, ROS 1 bags and rosbag2 folders all get chains; they are
//! composed by `crate::trajectory::tf_compose`.
//!
//! Choices (where nothing dictated one):
//! - Channels: those named `/tf` or `/tf_static` (with or without the leading `/`, as ROS 1 bags
//!   sometimes write them) whose type is a TF batch ([`is_tf_message`]). Edges on `/tf_static` are
//!   static (the latest one of a pair wins, as with latched `/tf_static` in ROS); a pair that ever
//!   appears on `/tf` is dynamic.
//! - Frame names are matched without a leading `/` (a ROS 1 habit): `/base_link` is `base_link`.
//! - TF is a tree: every child has one parent, the one of its latest edge. The chain between two
//!   frames goes up from PARENT to their lowest common ancestor, then down to CHILD.
//! - Memory: a big `/tf` (a legged robot's dozens of joints at 400 Hz) is not kept. Only pairs whose
//!   child is PARENT, CHILD or one of their ancestors (at the time the edge is read) keep their full
//!   history; every other pair keeps its latest edge only. A pair that joins the ancestry later (its
//!   parent link appeared late) therefore starts with the edge read last before it joined: chain
//!   samples before that edge are outside its span and dropped like any sample that would need
//!   extrapolation (counted in `ExtractedTopic::invalid_dropped`).
//! - `--stamp log` stamps every edge of a message with the message's log time.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use nalgebra::{Isometry3, Translation3};

use crate::decode::tf::{decode_tf_message, is_tf_message, TfEdge};
use crate::decode::Encoding;
use crate::error::{Error, Result};
use crate::sources::recording::ChannelInfo;
use crate::trajectory::tf_compose::{compose, Composed, EdgeSeries, Link};

/// The type name reported for a chain: the schema its edges come from. It is not a type trajdrift
/// patches in an annotated copy, so an aligned chain is written as PoseStamped from its samples.
pub const CHAIN_TYPE_NAME: &str = "tf2_msgs/msg/TFMessage";

/// A frame name as matched: without a leading `/`.
pub fn frame_name(name: &str) -> &str {
    name.trim_start_matches('/')
}

/// A requested chain: the pose of `child` in `parent`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChainRequest {
    /// The topic as the user wrote it, e.g. `/tf:map:base_link`.
    pub topic: String,
    pub parent: String,
    pub child: String,
}

/// `Some` when `topic` names a TF chain (`/tf:PARENT:CHILD` or `tf:PARENT:CHILD`): the request, or an
/// error when a frame is missing.
pub fn parse_chain_topic(topic: &str) -> Option<Result<ChainRequest>> {
    let rest = topic.strip_prefix("/tf:").or(topic.strip_prefix("tf:"))?;
    let parsed = rest
        .split_once(':')
        .map(|(p, c)| (frame_name(p), frame_name(c)))
        .filter(|(p, c)| !p.is_empty() && !c.is_empty() && p != c);
    Some(match parsed {
        Some((p, c)) => Ok(ChainRequest {
            topic: topic.to_string(),
            parent: p.to_string(),
            child: c.to_string(),
        }),
        None => Err(Error::InvalidArgument(format!(
            "{topic}: a TF chain is written /tf:PARENT:CHILD with two different frames, e.g. /tf:odom:base_link"
        ))),
    })
}

/// True for a channel whose TF edges chains use: `/tf` or `/tf_static` of a TF batch type in an
/// encoding trajdrift decodes.
pub fn is_tf_channel(c: &ChannelInfo) -> bool {
    matches!(frame_name(&c.topic), "tf" | "tf_static")
        && is_tf_message(&c.schema_name)
        && Encoding::from_name(&c.message_encoding).is_some()
}

/// True for the static TF channel.
pub fn is_static_channel(c: &ChannelInfo) -> bool {
    frame_name(&c.topic) == "tf_static"
}

/// Decodes one TF message of channel `c` (which must pass [`is_tf_channel`]).
pub fn decode_edges(path: &Path, c: &ChannelInfo, index: u64, data: &[u8]) -> Result<Vec<TfEdge>> {
    let encoding = Encoding::from_name(&c.message_encoding).unwrap_or(Encoding::Cdr);
    decode_tf_message(encoding, data).map_err(|detail| Error::Decode {
        path: path.to_path_buf(),
        topic: c.topic.clone(),
        index,
        detail,
    })
}

/// What is kept of one parent → child pair.
#[derive(Debug, Clone, Default)]
struct PairHistory {
    is_static: bool,
    stamps_ns: Vec<i64>,
    poses: Vec<Isometry3<f64>>,
    /// Edges read.
    read: u64,
}

impl PairHistory {
    fn keep_latest_only(&mut self) {
        if self.stamps_ns.len() > 1 {
            let n = self.stamps_ns.len() - 1;
            self.stamps_ns.drain(..n);
            self.poses.drain(..n);
        }
    }

    /// Sorts by stamp and drops repeated stamps (keeping the first read).
    fn sort_dedup(&mut self) {
        let mut idx: Vec<usize> = (0..self.stamps_ns.len()).collect();
        idx.sort_by_key(|&i| self.stamps_ns[i]);
        idx.dedup_by_key(|i| self.stamps_ns[*i]);
        self.stamps_ns = idx.iter().map(|&i| self.stamps_ns[i]).collect();
        self.poses = idx.iter().map(|&i| self.poses[i]).collect();
    }
}

/// Collects the TF edges the requested chains need during one pass (see the module doc for what is
/// kept).
#[derive(Debug, Default)]
pub struct TfCollector {
    /// PARENT and CHILD of every request.
    wanted: HashSet<String>,
    /// child → parent, from the latest edge of each child.
    parent_of: HashMap<String, String>,
    /// Children whose pairs keep their full history: wanted frames and their ancestors.
    relevant: HashSet<String>,
    /// (parent, child) → what is kept.
    pairs: HashMap<(String, String), PairHistory>,
    /// TF messages read.
    pub messages: u64,
}

impl TfCollector {
    /// A collector for `requests`.
    pub fn new(requests: &[ChainRequest]) -> Self {
        let wanted: HashSet<String> = requests
            .iter()
            .flat_map(|r| [r.parent.clone(), r.child.clone()])
            .collect();
        let mut c = TfCollector {
            wanted,
            ..TfCollector::default()
        };
        c.update_relevant();
        c
    }

    /// Recomputes the wanted frames' ancestry after the tree changed.
    fn update_relevant(&mut self) {
        let mut relevant = HashSet::new();
        for w in &self.wanted {
            let mut frame = w.as_str();
            // A cycle in bad data must not loop forever: a tree has at most `parent_of.len()` steps.
            for _ in 0..=self.parent_of.len() {
                if !relevant.insert(frame.to_string()) {
                    break;
                }
                match self.parent_of.get(frame) {
                    Some(p) => frame = p,
                    None => break,
                }
            }
        }
        // Pairs that stop being relevant (a re-parented frame) keep what they have.
        self.relevant = relevant;
    }

    /// Adds the edges of one TF message; `stamp_override` replaces their stamps (`--stamp log`).
    pub fn push(&mut self, is_static: bool, edges: Vec<TfEdge>, stamp_override: Option<i64>) {
        self.messages += 1;
        for e in edges {
            let parent = frame_name(&e.parent).to_string();
            let child = frame_name(&e.child).to_string();
            if parent.is_empty() || child.is_empty() || parent == child {
                continue;
            }
            if self.parent_of.get(&child) != Some(&parent) {
                self.parent_of.insert(child.clone(), parent.clone());
                self.update_relevant();
            }
            let relevant = self.relevant.contains(&child);
            let pair = self.pairs.entry((parent, child)).or_default();
            pair.read += 1;
            // A pair seen on /tf is dynamic from then on.
            pair.is_static = is_static && (pair.read == 1 || pair.is_static);
            if pair.is_static || !relevant {
                pair.stamps_ns.clear();
                pair.poses.clear();
            }
            pair.stamps_ns.push(stamp_override.unwrap_or(e.stamp_ns));
            pair.poses.push(Isometry3::from_parts(
                Translation3::from(e.translation),
                e.rotation,
            ));
            if !relevant {
                pair.keep_latest_only();
            }
        }
    }

    /// The tree as read, ready for chain look-ups.
    pub fn finish(mut self) -> TfTree {
        for pair in self.pairs.values_mut() {
            pair.sort_dedup();
        }
        TfTree {
            parent_of: self.parent_of,
            pairs: self.pairs,
        }
    }
}

/// The edges read, for chain look-ups.
#[derive(Debug, Default)]
pub struct TfTree {
    parent_of: HashMap<String, String>,
    pairs: HashMap<(String, String), PairHistory>,
}

/// One edge of a chain, as found in the tree.
struct Step<'a> {
    history: &'a PairHistory,
    inverse: bool,
}

/// A composed chain with what the report says about it.
#[derive(Debug, Clone)]
pub struct ChainTrajectory {
    pub composed: Composed,
    /// Edges read on the chain's pairs.
    pub edges_read: u64,
}

impl TfTree {
    /// `frame` and its ancestors, `frame` first.
    fn ancestry<'a>(&'a self, frame: &'a str) -> Vec<&'a str> {
        let mut out = vec![frame];
        let mut f = frame;
        while let Some(p) = self.parent_of.get(f) {
            if out.contains(&p.as_str()) {
                break;
            }
            out.push(p);
            f = p;
        }
        out
    }

    /// Every frame connected to `frame` (its tree), sorted.
    fn connected(&self, frame: &str) -> Vec<String> {
        let root = *self.ancestry(frame).last().unwrap_or(&frame);
        let mut frames: Vec<String> = self
            .parent_of
            .keys()
            .map(String::as_str)
            .chain(self.parent_of.values().map(String::as_str))
            .filter(|f| *self.ancestry(f).last().unwrap_or(f) == root)
            .map(str::to_string)
            .collect();
        frames.push(frame.to_string());
        frames.sort();
        frames.dedup();
        frames
    }

    fn knows(&self, frame: &str) -> bool {
        self.parent_of.contains_key(frame) || self.parent_of.values().any(|p| p == frame)
    }

    /// The edges from `from` to `to`, or a sentence saying why there is none.
    fn path(&self, from: &str, to: &str) -> std::result::Result<Vec<Step<'_>>, String> {
        let list = |v: Vec<String>| {
            const MAX: usize = 12;
            let more = v.len().saturating_sub(MAX);
            let mut s = v.into_iter().take(MAX).collect::<Vec<_>>().join(", ");
            if more > 0 {
                s.push_str(&format!(" and {more} more"));
            }
            s
        };
        for f in [from, to] {
            if !self.knows(f) {
                let mut all: Vec<String> = self.connected_all();
                all.sort();
                return Err(format!(
                    "frame `{f}` is in no /tf or /tf_static edge (frames: {})",
                    if all.is_empty() {
                        "none".into()
                    } else {
                        list(all)
                    }
                ));
            }
        }
        let up = self.ancestry(from);
        let down = self.ancestry(to);
        let Some((i, j)) = up
            .iter()
            .enumerate()
            .find_map(|(i, f)| down.iter().position(|g| g == f).map(|j| (i, j)))
        else {
            return Err(format!(
                "no TF chain from {from} to {to}: {from} is connected to [{}], {to} to [{}]",
                list(self.connected(from)),
                list(self.connected(to))
            ));
        };
        let mut steps = Vec::new();
        // Up from `from` to the common ancestor: each edge (parent → child) walked backwards.
        for k in 0..i {
            steps.push((up[k + 1], up[k], true));
        }
        // Down from the common ancestor to `to`.
        for k in (0..j).rev() {
            steps.push((down[k + 1], down[k], false));
        }
        steps
            .into_iter()
            .map(|(p, c, inverse)| {
                self.pairs
                    .get(&(p.to_string(), c.to_string()))
                    .map(|history| Step { history, inverse })
                    .ok_or_else(|| format!("the edge {p}→{c} has no sample"))
            })
            .collect()
    }

    fn connected_all(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .parent_of
            .keys()
            .chain(self.parent_of.values())
            .cloned()
            .collect();
        v.sort();
        v.dedup();
        v
    }

    /// The trajectory of `request.child` in `request.parent`. Errors name the recording and the
    /// chain, and say which frames each end is connected to when there is a gap.
    pub fn chain(&self, path: &Path, request: &ChainRequest) -> Result<ChainTrajectory> {
        let err = |detail: String| Error::TfChain {
            path: path.to_path_buf(),
            topic: request.topic.clone(),
            detail,
        };
        let steps = self.path(&request.parent, &request.child).map_err(err)?;
        let links: Vec<Link<'_>> = steps
            .iter()
            .map(|s| Link {
                series: if s.history.is_static {
                    let p = s.history.poses.last().copied().unwrap_or_default();
                    EdgeSeries::Static(p)
                } else {
                    EdgeSeries::Dynamic {
                        stamps_ns: &s.history.stamps_ns,
                        poses: &s.history.poses,
                    }
                },
                inverse: s.inverse,
            })
            .collect();
        let composed = compose(&links).ok_or_else(|| {
            err(format!(
                "every edge between {} and {} is static (/tf_static), so there is no trajectory; pick frames joined by at least one /tf edge",
                request.parent, request.child
            ))
        })?;
        Ok(ChainTrajectory {
            composed,
            edges_read: steps.iter().map(|s| s.history.read).sum(),
        })
    }

    /// The constant pose of `to` in `from` from `/tf_static` edges only (for `tf-static:` levers).
    pub fn static_transform(
        &self,
        from: &str,
        to: &str,
    ) -> std::result::Result<Isometry3<f64>, String> {
        let steps = self.path(frame_name(from), frame_name(to))?;
        let mut pose = Isometry3::identity();
        for s in &steps {
            if !s.history.is_static {
                return Err(format!(
                    "the chain from {from} to {to} has a /tf (moving) edge, so {to} has no fixed offset in {from}"
                ));
            }
            let p = s.history.poses.last().copied().unwrap_or_default();
            pose *= if s.inverse { p.inverse() } else { p };
        }
        Ok(pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{UnitQuaternion, Vector3};

    fn edge(parent: &str, child: &str, stamp_ns: i64, x: f64) -> TfEdge {
        TfEdge {
            parent: parent.into(),
            child: child.into(),
            stamp_ns,
            translation: Vector3::new(x, 0.0, 0.0),
            rotation: UnitQuaternion::identity(),
        }
    }

    fn request(topic: &str) -> ChainRequest {
        parse_chain_topic(topic).unwrap().unwrap()
    }

    #[test]
    fn topics_parse() {
        let r = request("/tf:/map:base_link");
        assert_eq!((r.parent.as_str(), r.child.as_str()), ("map", "base_link"));
        assert!(parse_chain_topic("/estimate/odom").is_none());
        assert!(parse_chain_topic("/tf:odom").unwrap().is_err());
        assert!(parse_chain_topic("/tf:odom:odom").unwrap().is_err());
    }

    #[test]
    fn only_the_ancestry_keeps_its_history() {
        let r = request("/tf:map:base_link");
        let mut c = TfCollector::new(std::slice::from_ref(&r));
        for i in 0..10 {
            c.push(
                false,
                vec![
                    edge("/odom", "/base_link", i, i as f64),
                    edge("base_link", "leg", i, 0.0),
                    edge("map", "odom", i, 100.0),
                ],
                None,
            );
        }
        c.push(true, vec![edge("base_link", "imu", 0, 0.2)], None);
        let tree = c.finish();
        let kept = |p: &str, ch: &str| tree.pairs[&(p.to_string(), ch.to_string())].stamps_ns.len();
        assert_eq!(kept("odom", "base_link"), 10);
        assert_eq!(kept("map", "odom"), 10);
        assert_eq!(kept("base_link", "leg"), 1);
        let t = tree.chain(Path::new("x.mcap"), &r).unwrap();
        assert_eq!(t.composed.trajectory.len(), 10);
        assert_eq!(t.composed.trajectory.positions[3].x, 103.0);
        // The static imu mount in base_link; odom→imu crosses a moving edge.
        let s = tree.static_transform("base_link", "imu").unwrap();
        assert_eq!(s.translation.vector.x, 0.2);
        assert!(tree.static_transform("odom", "imu").is_err());
    }

    #[test]
    fn a_pair_that_joins_late_starts_at_its_last_edge() {
        // map→odom is read before odom→base_link links odom to the chain: only its latest edge (stamp
        // 4) was kept then, so base_link stamps before 4 are outside its span and dropped.
        let r = request("/tf:map:base_link");
        let mut c = TfCollector::new(std::slice::from_ref(&r));
        for i in 0..5 {
            c.push(false, vec![edge("map", "odom", i, 0.0)], None);
        }
        for i in 0..10 {
            c.push(false, vec![edge("odom", "base_link", i, 1.0)], None);
        }
        c.push(false, vec![edge("map", "odom", 100, 0.0)], None);
        let t = c.finish().chain(Path::new("x.mcap"), &r).unwrap();
        assert_eq!(t.composed.trajectory.stamps_ns, (4..10).collect::<Vec<_>>());
        assert_eq!(t.composed.outside_span, 4);
    }

    #[test]
    fn a_gap_names_both_sides() {
        let r = request("/tf:map:base_link");
        let mut c = TfCollector::new(std::slice::from_ref(&r));
        c.push(false, vec![edge("odom", "base_link", 0, 0.0)], None);
        c.push(false, vec![edge("map", "gps", 0, 0.0)], None);
        let e = c
            .finish()
            .chain(Path::new("x.mcap"), &r)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "x.mcap: /tf:map:base_link: no TF chain from map to base_link: map is connected to [gps, map], base_link to [base_link, odom]; run `trajdrift topics x.mcap` to list the TF frame pairs"
        );
    }
}

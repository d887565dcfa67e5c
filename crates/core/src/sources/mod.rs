//! Sources: where trajectories come from.
//!
//! Every source (an MCAP recording, a TUM file, later ROS 1 bags and rosbag2 folders) answers the same two
//! questions through [`Source`]: which channels it holds, and the trajectories of the topics asked for.
//! Eval, annotate and batch never care where samples came from.

pub mod bag;
pub(crate) mod extract;
pub mod input;
pub mod mcap;
pub mod mission;
pub mod open;
pub mod recording;
pub(crate) mod rosbag2;
pub mod tum;

pub use open::{open, open_all};
pub mod euroc;
pub mod kitti;
pub mod mapped_csv;
pub mod text;
pub mod tf_chain;
pub mod tf_frames;

pub use crate::diag::Warning;
use crate::error::Result;
use crate::trajectory::Trajectory;

/// Which clock stamps a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StampSource {
    /// `header.stamp`: when the sensor measured (default).
    #[default]
    Header,
    /// The MCAP log time: when the recorder received it.
    Log,
}

/// What to extract, and how.
#[derive(Debug, Clone, Default)]
pub struct ExtractOptions {
    /// Which stamp to use.
    pub stamp: StampSource,
    /// Local ENU origin for `NavSatFix` topics: (latitude °, longitude °, ellipsoidal height m).
    /// `None`: the first valid fix of the first geodetic topic requested.
    pub origin: Option<[f64; 3]>,
    /// (FROM, TO) frame pairs whose constant `/tf_static` transform (TO's pose in FROM) is wanted, for
    /// `tf-static:` levers; answered in [`Extraction::static_transforms`] by the same pass.
    pub static_lookups: Vec<(String, String)>,
    /// Drop the orientations of these topics (positions only): 32 bytes a sample that nothing
    /// downstream reads (see the application's `trajdrift::eval::inputs`).
    pub positions_only: Vec<String>,
}

/// The answer to one [`ExtractOptions::static_lookups`] entry.
#[derive(Debug, Clone)]
pub struct StaticTransform {
    pub from: String,
    pub to: String,
    /// TO's pose in FROM, or why there is none (a gap, a moving edge, an unknown frame).
    pub pose: std::result::Result<nalgebra::Isometry3<f64>, String>,
}

/// One channel of a recording, as `trajdrift topics` lists it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TopicInfo {
    pub topic: String,
    /// Schema name, e.g. `geometry_msgs/msg/PoseStamped` (empty for schemaless channels).
    pub type_name: String,
    pub message_encoding: String,
    pub message_count: u64,
    /// True when trajdrift can read this channel as a trajectory.
    pub readable: bool,
    /// On a `/tf` or `/tf_static` row when asked for ([`tf_frames::attach`]): the frame pairs it
    /// carries.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_pairs: Vec<tf_frames::FramePair>,
    /// On the `/tf` row: the root → leaf chains a user can pass as `/tf:PARENT:CHILD`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tf_chains: Vec<String>,
}

/// The trajectory of one topic, with what was learned while reading it.
#[derive(Debug, Clone)]
pub struct ExtractedTopic {
    pub topic: String,
    pub type_name: String,
    pub trajectory: Trajectory,
    /// Messages read on the topic.
    pub messages: u64,
    /// Samples dropped as invalid (NO_FIX, NaN).
    pub invalid_dropped: u64,
    /// Samples dropped because their stamp repeated the previous one.
    pub duplicate_stamps: u64,
    /// Every row read, dropped per reason, stamps going back ([`crate::trajectory::rows`]).
    pub rows: crate::trajectory::rows::RowAudit,
    /// The ENU origin used for a geodetic topic.
    pub geodetic_origin: Option<[f64; 3]>,
}

/// The result of one streaming pass over a source.
#[derive(Debug, Clone, Default)]
pub struct Extraction {
    /// One entry per requested topic, in request order.
    pub topics: Vec<ExtractedTopic>,
    pub warnings: Vec<Warning>,
    /// One entry per [`ExtractOptions::static_lookups`] entry, in order.
    pub static_transforms: Vec<StaticTransform>,
}

/// Reports progress in bytes read so far.
pub type Progress<'a> = &'a (dyn Fn(u64) + Sync);

/// A recording (or text file) that trajectories can be read from.
pub trait Source {
    /// Size of the input in bytes (for progress bars and the report).
    fn size_bytes(&self) -> u64;
    /// The channels of the source.
    fn topics(&self) -> Result<Vec<TopicInfo>>;
    /// The type of `topic` when an index lists it without a pass over the messages (`None`: unknown
    /// without reading the file, or no such topic).
    fn indexed_type(&self, topic: &str) -> Option<String> {
        let _ = topic;
        None
    }
    /// Reads the trajectories of `topics` in one streaming pass. Memory follows the extracted samples.
    fn extract(
        &self,
        topics: &[String],
        options: &ExtractOptions,
        progress: Progress<'_>,
    ) -> Result<Extraction>;
    /// The TF frame pairs the source's `/tf` and `/tf_static` channels carry (one pass over those
    /// channels only); none for sources without TF (text files).
    fn frame_pairs(&self, progress: Progress<'_>) -> Result<Vec<tf_frames::FramePair>> {
        let _ = progress;
        Ok(Vec::new())
    }
    /// [`Source::frame_pairs`] by a pass over the whole recording, with the warnings that pass raised
    /// (a recording cut short), so `topics` can say the recording is damaged.
    fn frame_pairs_checked(
        &self,
        progress: Progress<'_>,
    ) -> Result<(Vec<tf_frames::FramePair>, Vec<Warning>)> {
        Ok((self.frame_pairs(progress)?, Vec::new()))
    }
}

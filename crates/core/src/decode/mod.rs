//! Message decoding: bytes of one message → a pose or a position sample.
//!
//! [`cdr`] reads ROS 2 CDR, [`ros1`] ROS 1 serialization, [`tf`] turns TF messages into edges, [`ros2_msgs`] holds the message layouts, `sample` picks the layout by
//! schema name and yields a [`Sample`], `geodesy` turns latitude/longitude into local ENU metres, and
//! [`ros2_schemas`] holds the schema texts needed to write MCAP files.

pub mod cdr;
pub(crate) mod geodesy;
pub mod ros1;
pub mod ros2_msgs;
pub(crate) mod ros2_prefix;
pub mod ros2_schemas;
pub(crate) mod sample;
pub mod tf;

pub use sample::{
    decode_message, decode_sample, message_kind, supported_types, Encoding, MessageKind, Sample,
    SamplePosition,
};

//! Message decoding: bytes of one message → a pose or a position sample.
//!
//! [`cdr`] reads ROS 2 CDR, [`ros2_msgs`] holds the message layouts, [`sample`] picks the layout by
//! schema name and yields a [`Sample`], [`geodesy`] turns latitude/longitude into local ENU metres, and
//! [`ros2_schemas`] holds the schema texts needed to write MCAP files.

pub mod cdr;
pub mod geodesy;
pub mod ros2_msgs;
pub mod ros2_schemas;
pub mod sample;

pub use sample::{
    decode_sample, message_kind, supported_types, MessageKind, Sample, SamplePosition,
};

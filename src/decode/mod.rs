//! Message decoding: bytes of one message → a pose or a position sample.

pub mod ros2_msgs;

//! Message decoding of every supported type, CDR (ROS 2) and ROS 1 serialization.
#![no_main]

use libfuzzer_sys::fuzz_target;
use trajdrift_core::decode::{decode_message, Encoding, MessageKind};

const KINDS: [MessageKind; 6] = [
    MessageKind::PoseStamped,
    MessageKind::PointStamped,
    MessageKind::Odometry,
    MessageKind::NavSatFix,
    MessageKind::PoseWithCovarianceStamped,
    MessageKind::TransformStamped,
];

fuzz_target!(|data: &[u8]| {
    for kind in KINDS {
        for encoding in [Encoding::Cdr, Encoding::Ros1] {
            let _ = decode_message(kind, encoding, data);
        }
    }
});

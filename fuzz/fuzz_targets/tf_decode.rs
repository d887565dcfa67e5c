//! TF decoding: `tf2_msgs/TFMessage` and `TransformStamped`, CDR and ROS 1.
#![no_main]

use libfuzzer_sys::fuzz_target;
use trajdrift_core::decode::tf::{decode_tf_message, decode_transform_stamped};
use trajdrift_core::decode::Encoding;

fuzz_target!(|data: &[u8]| {
    for encoding in [Encoding::Cdr, Encoding::Ros1] {
        let _ = decode_tf_message(encoding, data);
        let _ = decode_transform_stamped(encoding, data);
    }
});

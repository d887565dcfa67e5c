//! The ROS 1 bag reader: header, index, record pass, chunks (none/bz2/lz4), extraction, TF frames.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use trajdrift_core::sources::bag::BagSource;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch(data, "bag");
    if let Ok(source) = BagSource::open(&path) {
        common::exercise(&source);
    }
});

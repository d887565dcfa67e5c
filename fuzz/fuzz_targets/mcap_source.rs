//! The MCAP source: open (magic), summary, streaming pass, extraction, TF frames.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use trajdrift_core::sources::mcap::McapSource;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch(data, "mcap");
    if let Ok(source) = McapSource::open(&path) {
        common::exercise(&source);
    }
});

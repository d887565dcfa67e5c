//! The batch manifest and preset readers: TOML parsing, the parameter layers checked key by key, the
//! mission names, the list bounds. The first byte picks the reader (manifest or preset file).
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let path = common::scratch(rest, "toml");
    trajdrift::fuzzing::read_manifest_or_preset(&path, pick % 2 == 0);
});

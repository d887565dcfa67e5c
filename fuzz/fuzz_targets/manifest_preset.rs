//! The batch manifest and preset readers: TOML parsing, the parameter layers checked key by key, the
//! mission names, the list bounds. The first byte picks the reader (manifest or preset file).
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use trajdrift::batch::manifest::Manifest;
use trajdrift::eval::parameters::Parameters;
use trajdrift::eval::preset::Preset;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let path = common::scratch(rest, "toml");
    if pick % 2 == 0 {
        let _ = Manifest::from_toml(&path, &Parameters::default());
    } else {
        let _ = Preset::load(&path.to_string_lossy());
    }
});

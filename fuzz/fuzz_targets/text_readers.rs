//! The text readers behind one door: format detection, TUM, KITTI, EuRoC, CSV. The first byte picks
//! the file's extension (`.tum`, `.csv`, `.txt`) so detection by extension is covered too.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use trajdrift_core::sources::text::{read_text, TextOptions};

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let ext = ["tum", "csv", "txt"][pick as usize % 3];
    let path = common::scratch(rest, ext);
    let _ = read_text(&path, &TextOptions::default());
});

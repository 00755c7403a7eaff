//! Fuzzes the scene parser and validator, and renders whatever parses (tiny).
//!
//! `cargo fuzz run --sanitizer none parse_scene fuzz/corpus/parse_scene`
#![no_main]

use libfuzzer_sys::fuzz_target;

include!("../tiny_render.rs");

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        tiny_render(text);
    }
});

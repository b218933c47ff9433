//! cargo-fuzz target `micro_scene`: see `bodies::micro_scene` (shared with `tests/fuzz_corpus.rs`).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::micro_scene(data));

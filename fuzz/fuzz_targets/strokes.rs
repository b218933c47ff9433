//! cargo-fuzz target `strokes`: see `bodies::strokes` (shared with `tests/fuzz_corpus.rs`).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::strokes(data));

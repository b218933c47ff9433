//! cargo-fuzz target `inset`: see `bodies::inset` (shared with `tests/fuzz_corpus.rs`).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::inset(data));

//! cargo-fuzz target `texture_ratings`: see `bodies::texture_ratings` (shared with `tests/fuzz_corpus.rs`).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::texture_ratings(data));

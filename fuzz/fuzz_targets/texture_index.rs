//! cargo-fuzz target `texture_index`: see `bodies::texture_index` (shared with `tests/fuzz_corpus.rs`).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::texture_index(data));

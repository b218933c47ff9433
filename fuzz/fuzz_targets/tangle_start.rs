//! cargo-fuzz target `tangle_start`: see `bodies::tangle_start` (shared with `tests/fuzz_corpus.rs`).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::tangle_start(data));

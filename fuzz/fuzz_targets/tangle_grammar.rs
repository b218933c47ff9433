//! cargo-fuzz target `tangle_grammar`: see `bodies::tangle_grammar` (shared with `tests/fuzz_corpus.rs`).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::tangle_grammar(data));

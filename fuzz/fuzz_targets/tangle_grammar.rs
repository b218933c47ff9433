//! cargo-fuzz target `tangle_grammar`: see `bodies::tangle_grammar` (shared with `tests/fuzz_corpus.rs`),
//! with its CPU-time cost oracles on. Run with `-malloc_limit_mb=512 -rss_limit_mb=1024` (README).
#![no_main]

#[path = "../bodies.rs"]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // The CPU-time cost oracles (see `bodies::CPU_ORACLES`): on when fuzzing.
    bodies::CPU_ORACLES.store(true, std::sync::atomic::Ordering::Relaxed);
    bodies::tangle_grammar(data)
});

#!/usr/bin/env bash
# Release wasm build: one module per tool (the `filigree-wasm` crate in
# src/wasm/, one feature per tool) → wasm-opt → wasm-bindgen --target web →
# pkg/filigree_<tool>.js + pkg/filigree_<tool>_bg.wasm; then the code editor
# bundle and the page bundle (scripts/bundle.mjs) and the service worker's precache
# manifest (content hashes of every shipped file). The library is compiled
# once; each tool's build links it, and link-time optimisation keeps only
# what that tool's `start_job` reaches.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
MODULES="inspect pixel fit tangle tangle-png micro texture"
out=target/wasm32-unknown-unknown/release/filigree_wasm.wasm
mkdir -p target/wasm-modules
rm -rf pkg
# Tangle's module is linked for size: its link-time optimisation (the
# filigree-wasm crate's opt-level, which fat LTO applies to the whole
# module; the library and its dependencies are the same -O3 bitcode) runs
# at "s". 1,435,734 → 1,252,333 bytes (536 → 482 KB by gzip -9), and in
# tests/e2e/tangle-latency.bench.mjs, both builds in one session, nothing
# slower: village grown in the worker 943 → 883 ms, the baseline grid's
# median 249 → 189 ms, a leaf edit 18.5 → 15.7 ms. (Its expansion is
# branchy geometry, not the vectorised loops of Fit, Micro and Texture,
# which stay at -O3.) The other modules are unchanged; a Tangle answer is
# the same bytes (no opt-level reorders IEEE operations).
opt_level() { case "$1" in tangle) echo '"s"' ;; *) echo 3 ;; esac; }
for m in $MODULES; do
  cargo build --release -p filigree-wasm --target wasm32-unknown-unknown --features "$m" \
    --config "profile.release.package.filigree-wasm.opt-level=$(opt_level "$m")"
  wasm="target/wasm-modules/filigree_$m.wasm"
  cp "$out" "$wasm"
  # Smaller and faster: binaryen's optimiser, run on cargo's output BEFORE
  # wasm-bindgen. (After it, Debian's wasm-opt 108 rewrites the export of
  # wasm-bindgen's externref table to point at the function table, and every
  # call that passes a JS value fails.) wasm-opt 108 needs the features today's
  # Rust output uses named explicitly. FILIGREE_WASM_OPT=0 skips it.
  if [ "${FILIGREE_WASM_OPT:-1}" != 0 ]; then
    wasm-opt -O3 --enable-simd --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
      --enable-mutable-globals --enable-reference-types "$wasm" -o "$wasm.opt"
    echo "build: $m: wasm-opt -O3 $(stat -c %s "$wasm") → $(stat -c %s "$wasm.opt") bytes (at $SECONDS s of the build)"
    mv "$wasm.opt" "$wasm"
  fi
  wasm-bindgen --target web --no-typescript --out-dir pkg --out-name "filigree_$m" "$wasm"
done
node scripts/bundle.mjs
node scripts/precache.mjs
# FILIGREE_TEST_HOOKS=1: also an Inspect module with the test-only request
# kind `debug-abort` (feature test-hooks) in pkg-test/, which the e2e tests
# that need a deliberate crash serve in place of pkg/'s. pkg/ never has it.
# Its link optimises at -O1 (the library and the dependencies are the same
# -O3 bitcode as pkg/'s; only the link-time pass is lighter): 14 s of CPU
# at -O3, 7 s at -O1, for a module the tests only need to run.
if [ "${FILIGREE_TEST_HOOKS:-}" = 1 ]; then
  cargo build --release -p filigree-wasm --target wasm32-unknown-unknown --features inspect,test-hooks \
    --config "profile.release.package.filigree-wasm.opt-level=1"
  rm -rf pkg-test
  wasm-bindgen --target web --no-typescript --out-dir pkg-test --out-name filigree_inspect "$out"
  echo "build: pkg-test/ ready (test hooks)"
fi
for m in $MODULES; do
  printf 'build: pkg/filigree_%s_bg.wasm %d KiB (%d KiB gzipped)\n' "$m" \
    $(( $(stat -c %s "pkg/filigree_${m}_bg.wasm") / 1024 )) $(( $(gzip -9c "pkg/filigree_${m}_bg.wasm" | wc -c) / 1024 ))
done

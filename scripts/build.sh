#!/usr/bin/env bash
# Release wasm build: cargo → wasm-opt → wasm-bindgen --target web → pkg/, then the
# code editor bundle (scripts/bundle-editor.mjs) and the service worker's
# precache manifest (content hashes of every shipped file).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --lib --target wasm32-unknown-unknown --no-default-features --features web
wasm=target/wasm32-unknown-unknown/release/filigree.wasm
# Smaller and faster: binaryen's optimiser, run on cargo's output BEFORE
# wasm-bindgen. (After it, Debian's wasm-opt 108 rewrites the export of
# wasm-bindgen's externref table to point at the function table, and every
# call that passes a JS value fails.) wasm-opt 108 needs the features today's
# Rust output uses named explicitly. FILIGREE_WASM_OPT=0 skips it.
if [ "${FILIGREE_WASM_OPT:-1}" != 0 ]; then
  mkdir -p target/wasm-opt
  wasm-opt -O3 --enable-simd --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
    --enable-mutable-globals --enable-reference-types "$wasm" -o target/wasm-opt/filigree.wasm
  echo "build: wasm-opt -O3 $(stat -c %s "$wasm") → $(stat -c %s target/wasm-opt/filigree.wasm) bytes"
  wasm=target/wasm-opt/filigree.wasm
fi
rm -rf pkg
wasm-bindgen --target web --no-typescript --out-dir pkg "$wasm"
node scripts/bundle-editor.mjs
node scripts/precache.mjs
# FILIGREE_TEST_HOOKS=1: also a core with the test-only request kinds
# (`debug-abort`, feature test-hooks) in pkg-test/, which the e2e tests that
# need a deliberate crash serve in place of pkg/. pkg/ never has them.
if [ "${FILIGREE_TEST_HOOKS:-}" = 1 ]; then
  cargo build --release --lib --target wasm32-unknown-unknown --no-default-features --features web,test-hooks
  rm -rf pkg-test
  wasm-bindgen --target web --no-typescript --out-dir pkg-test target/wasm32-unknown-unknown/release/filigree.wasm
  echo "build: pkg-test/ ready (test hooks)"
fi
echo "build: pkg/ ready ($(du -k pkg/filigree_bg.wasm | cut -f1) KiB wasm)"

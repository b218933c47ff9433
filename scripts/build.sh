#!/usr/bin/env bash
# Release wasm build: cargo → wasm-bindgen --target web → pkg/, then the
# service worker's precache manifest (content hashes of every shipped file).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --lib --target wasm32-unknown-unknown --no-default-features --features web
rm -rf pkg
wasm-bindgen --target web --no-typescript --out-dir pkg target/wasm32-unknown-unknown/release/filigree.wasm
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

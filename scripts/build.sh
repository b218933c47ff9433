#!/usr/bin/env bash
# Release wasm build: cargo → wasm-bindgen --target web → pkg/, then the
# code editor bundle (scripts/bundle-editor.mjs) and the service worker's
# precache manifest (content hashes of every shipped file).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo build --release --lib --target wasm32-unknown-unknown --no-default-features --features web
rm -rf pkg
wasm-bindgen --target web --no-typescript --out-dir pkg target/wasm32-unknown-unknown/release/filigree.wasm
node scripts/bundle-editor.mjs
node scripts/precache.mjs
echo "build: pkg/ ready ($(du -k pkg/filigree_bg.wasm | cut -f1) KiB wasm)"

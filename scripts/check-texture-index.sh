#!/usr/bin/env bash
# The shipped Texture index (assets/texture-index.bin) is committed so a
# fresh clone serves the app at once; this check rebuilds it from scratch
# with the default settings and fails unless the bytes are the same, so the
# file in git is always what the code builds. It uses the dev binary that
# `cargo test` has built (our code at -O2 there, see Cargo.toml: at -O1
# loops are not vectorised and the build takes many minutes).
set -euo pipefail
cd "$(dirname "$0")/.."
# FILIGREE_BIN names a binary to use instead (check.sh passes a copy of
# the dev binary, so that it can build on while this runs).
bin=${FILIGREE_BIN:-}
if [ -z "$bin" ]; then
  cargo build --quiet --bin filigree
  bin=target/debug/filigree
fi
out=target/texture-index.rebuilt.bin
start=$(date +%s)
"$bin" build-index --out "$out" > target/texture-index.rebuilt.json
echo "texture index rebuilt in $(( $(date +%s) - start )) s: $(grep -E '"(bytes|id)"' target/texture-index.rebuilt.json | tr -d ' \n')"
if ! cmp -s "$out" assets/texture-index.bin; then
  echo "assets/texture-index.bin is not what the code builds ($(stat -c %s assets/texture-index.bin) vs $(stat -c %s "$out") bytes)." >&2
  echo "Rebuild and commit it: cargo run --release -- build-index --out assets/texture-index.bin" >&2
  exit 1
fi
echo "texture index: the committed asset is what the code builds"

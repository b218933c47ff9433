#!/usr/bin/env bash
# The shipped Texture index (assets/texture-index.bin) is committed so a
# fresh clone serves the app at once. assets/texture-index.inputs records
# the hash of everything the build reads (scripts/texture-index-inputs.sh)
# and the index's own hash, both as of the last time the index was rebuilt
# and found to be what the code builds. When both still hold, the index is
# what the code builds and this check ends at once. Otherwise it rebuilds
# the index from scratch with the default settings and fails unless the
# bytes are the same (then `bash scripts/bless.sh texture-index` records the
# new inputs, or writes the new index after an intended change). It uses the
# dev binary that `cargo test` has built (our code at -O2 there, see
# Cargo.toml: at -O1 loops are not vectorised and the build takes many minutes).
# With --unchanged it only compares the hashes: exit 0 when the index needs no
# rebuild, 1 when it does (check.sh then builds the CLI and runs the rebuild).
set -euo pipefail
cd "$(dirname "$0")/.."
inputs=$(bash scripts/texture-index-inputs.sh)
index=$(sha256sum assets/texture-index.bin | cut -c1-64)
recorded_inputs=$(awk '$1 == "inputs" {print $2}' assets/texture-index.inputs 2>/dev/null || true)
recorded_index=$(awk '$1 == "index" {print $2}' assets/texture-index.inputs 2>/dev/null || true)
if [ "$inputs" = "$recorded_inputs" ] && [ "$index" = "$recorded_index" ]; then
  echo "texture index: its inputs are unchanged since it was built (inputs $inputs); not rebuilt"
  exit 0
fi
if [ "${1:-}" = --unchanged ]; then exit 1; fi
if [ "$index" != "$recorded_index" ]; then
  echo "texture index: assets/texture-index.bin is not the file recorded in assets/texture-index.inputs; rebuilding"
else
  echo "texture index: its inputs changed (inputs $inputs, recorded ${recorded_inputs:-none}); rebuilding"
fi
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
  echo "If the change is intended: bash scripts/bless.sh texture-index (writes it and records its inputs), then commit both." >&2
  exit 1
fi
echo "texture index: the committed asset is what the code builds"
if [ "$inputs" != "$recorded_inputs" ]; then
  echo "texture index: record the new inputs so the next run skips the rebuild: bash scripts/bless.sh texture-index" >&2
  if [ -n "${FILIGREE_STRICT_INPUTS:-}" ]; then exit 1; fi
fi

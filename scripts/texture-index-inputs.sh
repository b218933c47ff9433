#!/usr/bin/env bash
# Prints the hash of everything `filigree build-index` reads to make the
# Texture index: the code of the layers it uses (tests/layers.rs: texture
# uses core, raster and geom; the CLI's build-index command and its
# defaults) and the locked dependency versions. The hash is recorded in
# assets/texture-index.inputs beside the index; scripts/check-texture-index.sh
# rebuilds the index only when it differs (scripts/bless.sh texture-index
# records a new one after a rebuild gives the committed bytes or new ones).
set -euo pipefail
cd "$(dirname "$0")/.."
{
  find src/texture src/core src/raster src/geom -type f -name '*.rs' -print
  echo src/cli/cmd/texture_index.rs
  echo src/cli/main.rs
  echo Cargo.lock
} | LC_ALL=C sort | xargs sha256sum | sha256sum | cut -c1-64

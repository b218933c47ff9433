#!/usr/bin/env bash
# The one command that rewrites goldens after an intended change. Look at
# what it wrote (git diff, the PNGs) before committing.
#   bash scripts/bless.sh [all | pixel | fit | micro | tangle | texture-index]...
# Every golden and what checks it besides our own code:
#   pixel          tests/golden/pixel/*.png      the browser's bytes (tests/e2e/pixel.test.mjs)
#   fit            tests/golden/fit/*.{png,svg}  none (our renderer's own output)
#   micro          tests/fixtures/micro-native/  the browser's bytes (tests/e2e/micro*.test.mjs)
#   tangle         tests/golden/tangle-leaf-seed1.svg.sha256, tangle-leaf-seed1-800.png.sha256
#                                                the browser's SVG export (tests/e2e/tangle.test.mjs)
#                                                and PNG export (tests/e2e/tangle-png.test.mjs)
#   texture-index  assets/texture-index.bin + .inputs
#                                                none (rebuilt from scratch when its inputs change,
#                                                scripts/check-texture-index.sh)
# Rust tests read FILIGREE_BLESS=1 (the only variable that blesses).
set -euo pipefail
cd "$(dirname "$0")/.."
what=("$@")
[ ${#what[@]} -eq 0 ] && what=(all)
want() { for w in "${what[@]}"; do [ "$w" = all ] || [ "$w" = "$1" ] && return 0; done; return 1; }
# The integration tests are one binary (tests/main.rs); a file's tests are
# those under its module path (a filter matches anywhere in a name, so Fit's
# skips Micro's `micro_fit::`).
filters=()
want pixel && filters+=(pixel::)
want fit && filters+=(fit:: --skip micro_fit::)
want micro && filters+=(micro:: micro_fit::)
if [ ${#filters[@]} -gt 0 ]; then
  FILIGREE_BLESS=1 cargo test --test integration -- "${filters[@]}"
fi
if want tangle || want texture-index; then
  cargo build --quiet --bin filigree
fi
if want tangle; then
  svg=target/tangle-leaf-seed1.svg
  target/debug/filigree tangle --grammar assets/tangle/leaf.tangle --seed 1 --out "$svg" > /dev/null
  echo "$(sha256sum "$svg" | cut -c1-64) $(stat -c %s "$svg")" > tests/golden/tangle-leaf-seed1.svg.sha256
  echo "bless: tests/golden/tangle-leaf-seed1.svg.sha256"
  png=target/tangle-leaf-seed1-800.png
  target/debug/filigree tangle --grammar assets/tangle/leaf.tangle --seed 1 --png-width 800 --out "$png" > /dev/null
  echo "$(sha256sum "$png" | cut -c1-64) $(stat -c %s "$png")" > tests/golden/tangle-leaf-seed1-800.png.sha256
  echo "bless: tests/golden/tangle-leaf-seed1-800.png.sha256"
fi
if want texture-index; then
  target/debug/filigree build-index --out assets/texture-index.bin > target/texture-index.rebuilt.json
  printf 'inputs %s\nindex %s\n' "$(bash scripts/texture-index-inputs.sh)" \
    "$(sha256sum assets/texture-index.bin | cut -c1-64)" > assets/texture-index.inputs
  echo "bless: assets/texture-index.bin and assets/texture-index.inputs"
fi

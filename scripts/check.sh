#!/usr/bin/env bash
# Runs every check CI runs, in the same order, from a fresh clone on a fresh
# Debian machine with Rust: installs what is missing (Chromium via apt, npm dev
# dependencies, the wasm target and the matching wasm-bindgen-cli), then
# fmt, clippy (the workspace, -D warnings) inside the cargo test build, the
# cargo tests, the release
# wasm build (one module per tool), the texture index checked (rebuilt in
# the background, and compared with the committed one, only when its
# inputs changed), and the browser end-to-end tests in headless Chromium.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each step says when it starts (seconds since the start) and how busy the
# machine's cores were since the step before (core-seconds busy of those
# available, from /proc/stat), so a slow CI run shows where its time went
# and whether it waited or computed. (On this 2-core machine every phase
# keeps both cores 93-99% busy: CI time is its CPU work over the cores,
# docs/bench/ci-budget-2026-12-07.md.)
cpu_ticks() { [ -r /proc/stat ] && awk '/^cpu /{print $2+$3+$4+$7+$8+$9, $5+$6; exit}' /proc/stat || echo "0 0"; }
read -r busy_last idle_last <<< "$(cpu_ticks)"
step() {
  local busy idle hz
  read -r busy idle <<< "$(cpu_ticks)"
  hz=$(getconf CLK_TCK 2>/dev/null || echo 100)
  printf '\n== %s (at %d s; since the last step %d core-s busy of %d)\n' "$*" "$SECONDS" \
    $(( (busy - busy_last) / hz )) $(( (busy - busy_last + idle - idle_last) / hz ))
  busy_last=$busy idle_last=$idle
}
# A fresh clone has no incremental cache to reuse, and writing one costs:
# with the dev profile's `lto = "off"` (Cargo.toml), the native test build
# took 508 CPU-s incrementally and 435 without, in 16 codegen units a crate
# instead of 256.
export CARGO_INCREMENTAL=0

step "installing what is missing"
rustup component list --installed | grep -q '^clippy' || rustup component add clippy
rustup component list --installed | grep -q '^rustfmt' || rustup component add rustfmt
mkdir -p target
# The Rust side (the wasm target, and the wasm-bindgen CLI that cargo
# compiles for about two minutes on a new machine) runs beside apt and npm,
# which mostly wait on the network.
bash scripts/setup.sh rust > target/setup.log 2>&1 &
setup_rust=$!
packages=()
[ -x "${CHROMIUM_PATH:-/usr/bin/chromium}" ] || packages+=(chromium)
if [ "${FILIGREE_WASM_OPT:-1}" != 0 ] && ! command -v wasm-opt >/dev/null; then packages+=(binaryen); fi
if [ "${#packages[@]}" != 0 ]; then
  sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y "${packages[@]}"
fi
if [ ! -d node_modules/playwright-core ] || [ ! -d node_modules/esbuild ] || [ ! -d node_modules/@codemirror/view ] || [ ! -d node_modules/axe-core ]; then
  # The browser is Debian's; never let a tool download its own.
  PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund
fi
if ! wait "$setup_rust"; then
  cat target/setup.log
  exit 1
fi
cat target/setup.log

step "cargo fmt --check"
cargo fmt --all -- --check

# The release wasm build (one module per tool, and the test-hooks Inspect
# module) starts now and runs beside the native test build: they share no
# build directory, and it is one long chain that keeps a single core busy
# for long stretches (the library's one codegen unit, then each module's
# LTO link), while the test build and the tests leave a core idle at times (the
# final crate's check, the links, single-threaded test binaries). Started
# first, its chain ends sooner; together they take less than one after the
# other.
step "the release wasm build starts (in the background)"
FILIGREE_TEST_HOOKS=1 bash scripts/build.sh > target/wasm-build.log 2>&1 &   # pkg/ and the test-only pkg-test/
wasm_build=$!
trap 'kill "$wasm_build" 2>/dev/null || true' EXIT

# clippy runs inside the one native build: cargo hands the workspace's own
# crates (never a dependency) to clippy-driver, as `cargo clippy` does, and
# clippy-driver lints each one and then compiles it as rustc would. A
# separate `cargo clippy` checked every dependency and our crates once more
# before the test build compiled them (about 3 minutes of CI); now each is
# compiled once. What it covers is what `cargo clippy --workspace
# --all-targets` did: every target of both crates (the research probes
# under src/bench/examples too), natively, with the `web` boundary
# (src/web/) and the wasm crate's test hooks. The few
# `cfg(target_arch = "wasm32")` blocks are compiled by the release wasm
# build, which denies rustc's warnings (.cargo/config.toml). Clippy leaves
# MIR unoptimised (LLVM still optimises at -O2): the tests' numbers are
# the same, IEEE operations are never reordered.
lint_and_build() {
  RUSTC_WORKSPACE_WRAPPER="$(rustup which clippy-driver)" \
    CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__" \
    cargo "$@" --workspace --features filigree-wasm/inspect,filigree-wasm/test-hooks
}

step "the texture index: its inputs' hash, then (only when it changed) the rebuild in the background"
# The index is rebuilt only when the hash of its inputs differs from the
# one recorded beside it (scripts/check-texture-index.sh); then the rebuild
# is the longest single job (about 10 CPU-minutes, half of it training the
# SVMs). It runs at the lowest priority under the test and wasm builds, on
# what they leave idle. It reads a copy of the binary, so the builds below
# may replace it. When the hash holds, nothing is built here: `cargo test`
# builds the CLI with the rest.
index_check=""
if ! bash scripts/check-texture-index.sh --unchanged; then
  lint_and_build build --bin filigree
  cp target/debug/filigree target/filigree-index-check
  FILIGREE_BIN=target/filigree-index-check nice -n 19 bash scripts/check-texture-index.sh \
    > target/texture-index-check.log 2>&1 &
  index_check=$!
fi
# If a step below fails, the rebuild and the wasm build stop too.
trap 'pkill -f filigree-index-check 2>/dev/null || true; kill "$wasm_build" 2>/dev/null || true' EXIT

step "clippy and cargo test (one build), beside the release wasm build"
# `--tests`: the library's and the binary's unit tests and the integration
# tests (one binary, tests/main.rs); `--examples`: the research probes
# are built (linted) and have no tests to run. No doc tests (there are none).
lint_and_build test --tests --examples
step "the release wasm build (started before the tests) has ended"
if ! wait "$wasm_build"; then
  cat target/wasm-build.log
  exit 1
fi
cat target/wasm-build.log

# The rebuild gets both cores for what is left of it before the browser
# tests start: left running beside them, it doubled their time (nice 19 did
# not keep it out of Chromium's way).
step "the committed texture index is what the code builds"
if [ -n "$index_check" ]; then
  if ! wait "$index_check"; then
    cat target/texture-index-check.log
    exit 1
  fi
  cat target/texture-index-check.log
fi

step "browser end-to-end tests (headless Chromium)"
# Two test files at a time: one at a time left the second core idle for
# much of the suite (timers, page loads, waits on workers); two took 285–312 s
# against 400 s on this 2-core machine. The slowest test, micro-gl, then
# takes about 34 s of its 120 s wait (its frame timings are
# tests/e2e/micro-gl.bench.mjs's).
node --test --test-concurrency=2 tests/e2e/

step "all checks passed"

#!/usr/bin/env bash
# Installs what building the app needs, only when missing:
# the wasm32 target, the wasm-bindgen-cli whose version equals the
# wasm-bindgen crate in Cargo.lock (they must match exactly), and binaryen's
# wasm-opt (Debian package). `setup.sh rust` does the first two only
# (scripts/check.sh runs it beside its own apt and npm installs).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
  echo "setup: adding the wasm32-unknown-unknown target"
  rustup target add wasm32-unknown-unknown
fi

# The one place that reads the pinned version: Cargo.toml pins wasm-bindgen
# with "=", Cargo.lock records it, and the CLI must be that same version.
want=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
have=$(wasm-bindgen --version 2>/dev/null | awk '{print $2}' || true)
if [ "$have" != "$want" ]; then
  echo "setup: installing wasm-bindgen-cli $want (found '${have:-none}'); takes a few minutes"
  # Only the `wasm-bindgen` binary, without the test runner's TLS stack
  # (rustls and ring), at -O1: 109 s against 140 s for the default install
  # on this 2-core machine. It runs in a tenth of a second a module either
  # way, and writes the same bytes (checked on three modules).
  CARGO_PROFILE_RELEASE_OPT_LEVEL=1 \
    cargo install wasm-bindgen-cli --version "=$want" --no-default-features --bin wasm-bindgen
fi

if [ "${1:-}" != rust ] && [ "${FILIGREE_WASM_OPT:-1}" != 0 ] && ! command -v wasm-opt >/dev/null; then
  echo "setup: installing binaryen (wasm-opt) with apt"
  sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y binaryen
fi

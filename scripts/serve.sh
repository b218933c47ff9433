#!/usr/bin/env bash
# Set up (when needed), build the release wasm, and serve the app on
# http://localhost:${PORT:-8080}.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
exec node scripts/serve.mjs "${PORT:-8080}"

#!/usr/bin/env bash
# Set up (when needed), build the release wasm, and serve the app on
# http://localhost:${PORT:-8080}.
set -euo pipefail
cd "$(dirname "$0")/.."
# The program editor (CodeMirror) is bundled from npm packages at build time.
if [ ! -d node_modules/esbuild ] || [ ! -d node_modules/@codemirror/view ]; then
  PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund
fi
bash scripts/build.sh
exec node scripts/serve.mjs "${PORT:-8080}"

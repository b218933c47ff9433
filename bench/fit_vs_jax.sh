#!/usr/bin/env bash
# Fit throughput side by side with the JAX-on-CPU reference (issue 9 item 6).
#
#   bash bench/fit_vs_jax.sh [FILIGREE_BINARY]
#
# Runs `filigree bench fit --speed-only` on circles-grid and stripes-dots
# (one core, exporting each case), then bench/jax_fit_reference.py on the
# exported cases (one core, XLA single-threaded), and prints one JSON object
# with both figures, our/JAX ratios and the load. Needs a Python with jax:
# $JAX_PYTHON, or target/jax-venv/bin/python, made with
#   python3 -m venv target/jax-venv && target/jax-venv/bin/pip install jax jaxlib
# Nothing in the build or the tests needs JAX; only this script does.
# With BEFORE_BIN=<an older filigree binary>, its `bench fit --speed-only`
# runs in the same session too and the rows get after/before ratios.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-target/release/filigree}
PY=${JAX_PYTHON:-target/jax-venv/bin/python}
CPU=${BENCH_CPU:-0}
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
[ -x "$BIN" ] || { echo "no filigree binary at $BIN (cargo build --release)" >&2; exit 1; }
"$PY" -c 'import jax' 2>/dev/null || { echo "$PY cannot import jax (see the header)" >&2; exit 1; }
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
taskset -c "$CPU" "$BIN" bench fit --speed-only --only circles-grid,stripes-dots \
  --export-jax "$DIR/cases" >"$DIR/ours.json"
echo '{"throughput_one_core": []}' >"$DIR/before.json"
if [ -n "${BEFORE_BIN:-}" ]; then
  taskset -c "$CPU" "$BEFORE_BIN" bench fit --speed-only --only circles-grid,stripes-dots >"$DIR/before.json"
fi
XLA_FLAGS="--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1" \
  taskset -c "$CPU" "$PY" bench/jax_fit_reference.py "$DIR"/cases/*.json >"$DIR/jax.json"
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
"$PY" - "$DIR/ours.json" "$DIR/jax.json" "$load_before" "$load_after" "$DIR/before.json" <<'EOF'
import json, sys
ours = json.load(open(sys.argv[1]))["throughput_one_core"]
before = {(b["generator"], b["grid"]): b for b in json.load(open(sys.argv[5]))["throughput_one_core"]}
jax = {(c["generator"], c["grid"]): c for c in json.load(open(sys.argv[2]))["cases"]}
rows = []
for o in ours:
    j = jax.get((o["generator"], o["grid"]))
    if j is None:
        continue
    row = {"generator": o["generator"], "grid": o["grid"],
           "loss_filigree": j["loss_filigree"], "loss_jax_f64": j["f64"]["loss_jax"],
           "loss_rel_diff_f64": j["f64"]["loss_rel_diff"],
           "grad_max_rel_diff_f64": j["f64"]["grad_max_rel_diff"],
           "ours_loss_evals_per_s": o["loss_evals_per_s"],
           "ours_loss_grad_evals_per_s": o["loss_grad_evals_per_s"],
           "jax_loss_evals_per_s": j["jax_loss_evals_per_s"],
           "jax_loss_grad_evals_per_s": j["jax_loss_grad_evals_per_s"],
           "ratio_loss": round(o["loss_evals_per_s"] / j["jax_loss_evals_per_s"], 2),
           "ratio_loss_grad": round(o["loss_grad_evals_per_s"] / j["jax_loss_grad_evals_per_s"], 2)}
    for k in ("before_loss_evals_per_s", "before_loss_grad_evals_per_s"):
        if k in o:
            row["reference_path_" + k[len("before_"):]] = o[k]
    b = before.get((o["generator"], o["grid"]))
    if b is not None:
        row["before_binary_loss_evals_per_s"] = b["loss_evals_per_s"]
        row["before_binary_loss_grad_evals_per_s"] = b["loss_grad_evals_per_s"]
        row["after_over_before_loss"] = round(o["loss_evals_per_s"] / b["loss_evals_per_s"], 2)
        row["after_over_before_loss_grad"] = round(
            o["loss_grad_evals_per_s"] / b["loss_grad_evals_per_s"], 2)
    rows.append(row)
print(json.dumps({"bench": "fit_vs_jax", "load_before": sys.argv[3], "load_after": sys.argv[4],
                  "method": "best of three 0.3 s windows each, one core (taskset), JAX jit-compiled "
                            "and warmed up, faster of float64/float32",
                  "cases": rows}, indent=2))
EOF

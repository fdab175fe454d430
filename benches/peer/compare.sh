#!/usr/bin/env bash
# Runs one iterated CSG scenario in chisel and in Manifold, in the same run and
# on the same quantized tools, and prints both sets of figures and their ratios.
#
#   benches/peer/compare.sh mill 2000
#   benches/peer/compare.sh cheese 1000 [--seed 7]
#   benches/peer/compare.sh sweep 20
#   benches/peer/compare.sh cutter 2000 --path helix --sides 20
#   benches/peer/compare.sh fluted 1500 --flutes 3
#   benches/peer/compare.sh replay OPS.jsonl
#   benches/peer/compare.sh cheese 10000 --chisel-only
#
# Installs manifold3d with pip when it is missing, builds chisel with the bench
# profile (kernel overflow checks and debug assertions off), then hands over to
# compare.py. Extra arguments go to chisel (`--chisel-only`, `--json` and
# `--keep DIR` are compare.py's own).
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! python3 -c "import manifold3d" 2>/dev/null; then
    python3 -m pip install --quiet "manifold3d>=3.5,<3.6"
fi
target="${CARGO_TARGET_DIR:-target}"
CARGO_TARGET_DIR="$target" cargo build --quiet --profile bench -p chisel
exec python3 benches/peer/compare.py "$target/release/chisel" "$@"

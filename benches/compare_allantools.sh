#!/usr/bin/env bash
# Side by side with allantools on the same arrays (BENCHMARKS.md, "Allan engine").
# Installs allantools with pip into a throw-away virtual environment; nothing else relies on it.
#   bash benches/compare_allantools.sh
set -euo pipefail
# One thread for numpy as for allanscope (the issue compares one core with one core).
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
cd "$(dirname "$0")/.."
venv=${TMPDIR:-/tmp}/allanscope-bench-venv
data=${TMPDIR:-/tmp}/allanscope-stand.f64
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install --quiet allantools numpy
cargo build --release --example stand_run
ours=$(./target/release/examples/stand_run --write "$data" | tee /dev/stderr | sed -E 's/.*: ([0-9.]+) s$/\1/')
theirs=$("$venv/bin/python" benches/compare_allantools.py "$data" | tee /dev/stderr | sed -E 's/.*: ([0-9.]+) s$/\1/')
python3 -c "print(f'ratio allantools/allanscope (CPU time, same run): {float($theirs)/float($ours):.1f}x')"

#!/bin/bash
# Replay CPU / engine CPU, side by side (issue 15; BENCHMARKS.md "Decoding at the speed of the
# statistics"). Each round: the in-memory engine's CPU (examples/stand_run), then each binary's
# replay of the 3-hour siu8 capture (task-clock of all its threads). Medians and ranges per binary.
#
# usage: benches/replay/ratio.sh ROUNDS BIN...   (BIN: paths of allanscope binaries to compare)
# needs: perf; the capture made first with
#   target/release/allanscope simulate --model config/models/siu8_stand.toml --duration 3h \
#     --seed 1 --format siu8 -o /tmp/lab_siu8_3h.siu8
#   cargo build --release --example stand_run
set -eu
rounds=$1; shift
capture=${CAPTURE:-/tmp/lab_siu8_3h.siu8}
engine=${ENGINE:-target/release/examples/stand_run}
out=$(mktemp)
for _ in $(seq "$rounds"); do
  e=$("$engine" 2>&1 | grep -o "cpu: [0-9.]* s" | awk '{print $2}')
  echo "engine $e" >> "$out"
  for b in "$@"; do
    t=$(perf stat -x, -e task-clock "$b" analyze "$capture" --format siu8 2>&1 >/dev/null \
      | grep task-clock | cut -d, -f1)
    echo "$b $t $e" | awk '{printf "%s %.3f %.3f %.3f\n", $1, $2/1000, $3, $2/1000/$3}' >> "$out"
  done
done
echo "load: $(cut -d' ' -f1-3 /proc/loadavg)"
med() { sort -n | awk '{a[NR]=$1} END{m=(NR%2)?a[(NR+1)/2]:(a[NR/2]+a[NR/2+1])/2; printf "%.3f [%.3f-%.3f]", m, a[1], a[NR]}'; }
echo "engine CPU s: $(awk '$1=="engine"{print $2}' "$out" | med)"
for b in "$@"; do
  echo "$b: replay CPU s $(awk -v b="$b" '$1==b{print $2}' "$out" | med)  ratio $(awk -v b="$b" '$1==b{print $4}' "$out" | med)"
done
rm -f "$out"

#!/bin/bash
# usage: BINS="OLD NEW" cli_pair.sh MODEL DURATION TAU0 SEED...
# Simulates MODEL for DURATION with each seed (`allanscope simulate`, the first binary), then
# diagnoses the capture with each binary of BINS (paths to `allanscope` builds) and prints one
# line per binary and seed: verdict, G before -> after, the effects with their parameters,
# quantization_limited and the step's kind ("The dead band as model discrepancy (session 13)").
M=$1; DUR=$2; T0=$3; shift 3
set -- "$@"
read -r -a B <<< "${BINS:?set BINS to two allanscope binaries}"
for s in "$@"; do
  f=$(mktemp --suffix=.csv)
  "${B[0]}" simulate --model "$M" --duration "$DUR" --seed "$s" --format csv -o "$f" --force 2>/dev/null
  for b in "${B[@]}"; do
    "$b" diagnose "$f" --tau0 "$T0" --json 2>/dev/null | python3 -c '
import json, sys
b, s = sys.argv[1], sys.argv[2]
for l in sys.stdin:
    d = json.loads(l)
    if d.get("type") != "diagnosis":
        continue
    eff = [(e.get("kind"), e.get("params")) for e in d.get("effects", [])]
    q = (d.get("quantization") or {}).get("kind")
    print(b, "seed", s, d["verdict"], "G %.3f -> %.3f" % (d["gap_before"], d["gap_after"]), eff,
          "qlim", d.get("quantization_limited"), "q", q)
' "$b" "$s"
  done
  rm -f "$f"
done

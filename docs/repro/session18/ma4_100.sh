#!/bin/bash
# The MA4 study of issue 13's proof through the CLI: seeds 1001-1100, 2 h each, one line per
# seed (seed, verdict, G before, G after, named effects). usage: ma4_100.sh BIN MODEL OUT
BIN=$1; MODEL=$2; OUT=$3; T=$(mktemp -d)
for S in $(seq 1001 1100); do
  $BIN simulate --model "$MODEL" --duration 2h --seed $S --format csv -o "$T/ma4.csv" 2>/dev/null
  $BIN diagnose "$T/ma4.csv" --tau0 0.004 --unit m/s --json 2>/dev/null | python3 -c "
import json,sys
r=json.loads(sys.stdin.readline())
print($S, r['verdict'], round(r['gap_before'],3), round(r['gap_after'],3), '+'.join(e['kind'] for e in r['effects']) or '-')" >> "$OUT"
  rm -f "$T/ma4.csv"
done
rmdir "$T"

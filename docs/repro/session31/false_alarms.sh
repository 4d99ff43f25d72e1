#!/bin/bash
# usage: false_alarms.sh BIN MODEL FROM TO [UNIT]: one line per seed (seed, verdict, G before,
# G after, effects) for clean 1-h runs of MODEL at 400 Hz diagnosed through the CLI, the
# increments in UNIT (default rad). Session 31: phone_mems_gyro.toml seeds 201-300,
# phone_mems_acc.toml seeds 301-350 with UNIT m/s.
BIN=$1; MODEL=$2; FROM=$3; TO=$4; UNIT=${5:-rad}
T=$(mktemp -d)
for s in $(seq "$FROM" "$TO"); do
  "$BIN" simulate --model "$MODEL" --duration 1h --seed "$s" --format csv -o "$T/r.csv" --force >/dev/null 2>&1
  "$BIN" diagnose "$T/r.csv" --tau0 0.0025 --unit "$UNIT" 2>/dev/null | python3 -c "
import json, sys
for l in sys.stdin:
    r = json.loads(l)
    print($s, r['verdict'], round(r['gap_before'], 2), round(r['gap_after'], 2),
          ' '.join(e['kind'] for e in r['effects']))
"
done
rm -rf "$T"

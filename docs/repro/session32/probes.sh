#!/bin/bash
# usage: probes.sh BIN: session 32's unit families never drawn before, clean runs diagnosed through
# the CLI; one line per seed (seed, verdict, G before, G after, effects with parameters) in
# adxl_*.txt, auto24.txt, tac3.txt in the current folder. About 15 min on one core.
BIN=$1; HERE=$(cd "$(dirname "$0")" && pwd)
run() { # MODEL TAU0 DURATION FROM TO UNIT
  T=$(mktemp -d)
  for s in $(seq "$4" "$5"); do
    "$BIN" simulate --model "$1" --duration "$3" --seed "$s" --format csv -o "$T/r.csv" --force >/dev/null 2>&1
    "$BIN" diagnose "$T/r.csv" --tau0 "$2" --unit "$6" 2>/dev/null | python3 -c "
import json, sys
for l in sys.stdin:
    r = json.loads(l)
    print($s, r['verdict'], round(r['gap_before'], 2), round(r['gap_after'], 2),
          ' '.join(e['kind'] + json.dumps(e['params'], separators=(',', ':')) for e in r['effects']))
"
  done
  rm -rf "$T"
}
for L in 0.0383 0.084 0.126 0.306; do run "$HERE/adxl_$L.toml" 0.01 2h 1 30 m/s > "adxl_$L.txt"; done
run "$HERE/auto_gyro.toml" 0.01 24h 1 15 rad > auto24.txt
run "$HERE/tac_mems.toml" 0.001 3h 1 10 rad > tac3.txt

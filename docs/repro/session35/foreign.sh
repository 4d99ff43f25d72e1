#!/bin/bash
# usage: foreign.sh BIN FAMILY FIRST LAST: clean channels from foreign.py diagnosed through the
# CLI, one JSON line per seed (the truth, the verdict, G before and after, the effects, the fit's
# N, B, K with their intervals) on standard output.
BIN=$1; FAM=$2; HERE=$(cd "$(dirname "$0")" && pwd)
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
for s in $(seq "$3" "$4"); do
  truth=$(python3 "$HERE/foreign.py" "$FAM" "$s" "$T/r.csv")
  unit=$(echo "$truth" | python3 -c 'import json,sys; print(json.load(sys.stdin)["unit"])')
  tau0=$(echo "$truth" | python3 -c 'import json,sys; print(json.load(sys.stdin)["tau0"])')
  if echo "$truth" | grep -q '"write": "rates"'; then opts="--rate"; else opts="--tau0 $tau0"; fi
  start=$(date +%s.%N)
  "$BIN" diagnose "$T/r.csv" $opts --unit "$unit" --json > "$T/out.jsonl" 2> "$T/err"
  rc=$?; secs=$(echo "$(date +%s.%N) - $start" | bc)
  python3 - "$T/out.jsonl" "$truth" "$rc" "$secs" <<'PY'
import json, sys
recs = [json.loads(l) for l in open(sys.argv[1])]
truth = json.loads(sys.argv[2])
out = dict(truth=truth, rc=int(sys.argv[3]), secs=round(float(sys.argv[4]), 1))
for r in recs:
    if r["type"] == "diagnosis":
        out.update(verdict=r["verdict"], g0=round(r["gap_before"], 3), g1=round(r["gap_after"], 3),
                   effects=[[e["kind"], e["params"]] for e in r["effects"]])
        out["coef"] = dict(zip("QNBKR", (float("%.4g" % c) for c in r["final_coef"])))
print(json.dumps(out))
PY
done

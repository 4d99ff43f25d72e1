#!/bin/bash
# usage: runset.sh TAG BIN SET...   (SET names below); writes TAG_SET.{csv,txt,err} in $RUNS
# (default: the current folder) and a start/end line per set in runs.log. THREADS (default 2).
# Session 19 (plan.md): the filter families at seeds 181 and 191, then session 18's c6 and d6.
HERE=$(cd "$(dirname "$0")" && pwd)
TAG=$1; BIN=$2; shift 2
cd "${RUNS:-.}" || exit 1
N="--effects none --no-oracle --draws 40"
for S in "$@"; do
  case $S in
    f181a) A="--families accfilt,cicacc,zpexp,accgrav,adis,adistemp,bartfog,cicgyro --hours 1,2 --seed 181 $N";;
    f181b) A="--families kalgyro,kalacc,mimu --seed 181 $N";;
    f191a) A="--families accfilt,cicacc,zpexp,accgrav,adis,adistemp,bartfog,cicgyro --hours 1,2 --seed 191 $N";;
    f191b) A="--families kalgyro,kalacc,mimu --seed 191 $N";;
    c6|d6) "$HERE/../session18/runset.sh" "$TAG" "$BIN" "$S"; continue;;
    *) echo "unknown set $S"; continue;;
  esac
  echo "$(date -u +%H:%M:%S) start $TAG $S: $A" >> runs.log
  $BIN $A --threads "${THREADS:-2}" --csv "${TAG}_$S.csv" > "${TAG}_$S.txt" 2> "${TAG}_$S.err"
  echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
done

#!/bin/bash
# usage: runset.sh TAG BIN SET...; writes TAG_SET.{csv,txt,err} in $RUNS (default: the current
# folder) and a start/end line per set in runs.log. THREADS (default 2).
# Session 21 (plan.md): the eleven filter families at any seed, fSEEDa (eight families, 1-2 h)
# and fSEEDb (kalgyro, kalacc, mimu); other sets (f181a ... c6, d6) go to session 19's script.
HERE=$(cd "$(dirname "$0")" && pwd)
TAG=$1; BIN=$2; shift 2
cd "${RUNS:-.}" || exit 1
N="--effects none --no-oracle --draws 40"
for S in "$@"; do
  case $S in
    f[0-9]*a) A="--families accfilt,cicacc,zpexp,accgrav,adis,adistemp,bartfog,cicgyro --hours 1,2 --seed ${S:1:-1} $N";;
    f[0-9]*b) A="--families kalgyro,kalacc,mimu --seed ${S:1:-1} $N";;
    *) RUNS=$(pwd) "$HERE/../session19/runset.sh" "$TAG" "$BIN" "$S"; continue;;
  esac
  echo "$(date -u +%H:%M:%S) start $TAG $S: $A" >> runs.log
  $BIN $A --threads "${THREADS:-2}" --csv "${TAG}_$S.csv" > "${TAG}_$S.txt" 2> "${TAG}_$S.err"
  echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
done

#!/bin/bash
# usage: runset.sh TAG BIN SET...; writes TAG_SET.{csv,txt,err} in $RUNS (default: the current
# folder) and a start/end line per set in runs.log. THREADS (default 2).
# Session 22 (plan.md): the seventeen families without a filter of their own beyond session
# 18's six, 40 clean runs each at any seed, at the durations of their own rounds (session 18's
# "False alarms in the 26 other families"): uSEEDa (the five held-out families, 1 h),
# uSEEDb (hrmems, short, fog5k, thermfog), uSEEDc (qtzgyro, servoacc, rlg, navacc, hrg, coarse,
# 1-2 h), uSEEDd (lowrate, 1-3 h; long, 8-24 h). Other sets go to session 21's script.
HERE=$(cd "$(dirname "$0")" && pwd)
TAG=$1; BIN=$2; shift 2
cd "${RUNS:-.}" || exit 1
for S in "$@"; do
  N="--effects none --no-oracle --draws ${DRAWS:-40} --seed ${S:1:-1}"
  case $S in
    u[0-9]*a) A=("--families heldout --hours 1,1 $N");;
    u[0-9]*b) A=("--families hrmems,short,fog5k,thermfog $N");;
    u[0-9]*c) A=("--families qtzgyro,servoacc,rlg,navacc,hrg,coarse --hours 1,2 $N");;
    u[0-9]*d) A=("--families lowrate --hours 1,3 $N" "--families long $N");;
    *) RUNS=$(pwd) "$HERE/../session21/runset.sh" "$TAG" "$BIN" "$S"; continue;;
  esac
  i=0
  for a in "${A[@]}"; do
    i=$((i + 1)); out="${TAG}_$S"; [ ${#A[@]} -gt 1 ] && out="${out}$i"
    echo "$(date -u +%H:%M:%S) start $TAG $S: $a" >> runs.log
    $BIN $a --threads "${THREADS:-2}" --csv "$out.csv" > "$out.txt" 2> "$out.err"
    echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
  done
done

#!/bin/bash
# Per-thread CPU of one replay, as perf samples of 0.1 ms task-clock grouped by thread name
# (allanscope-anal: analysis, allanscope-deco: decoding, tokio-rt-worker: reader and final fits).
# usage: benches/replay/threads.sh BIN [extra analyze options]; CAPTURE as in ratio.sh
set -eu
b=$1; shift
capture=${CAPTURE:-/tmp/lab_siu8_3h.siu8}
data=$(mktemp)
perf record -q -o "$data" -e task-clock -c 100000 "$b" analyze "$capture" --format siu8 "$@" > /dev/null 2>&1
perf report -i "$data" -n --no-children --sort comm --stdio 2>/dev/null | grep -v "^#" \
  | awk -v b="$b" 'NF>=3{a[$3]=$2; t+=$2} END{printf "%s total %5d anal %5d deco %5d tokio %4d\n", b, t, a["allanscope-anal"], a["allanscope-deco"], a["tokio-rt-worker"]}'
rm -f "$data"

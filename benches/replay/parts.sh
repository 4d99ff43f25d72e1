#!/bin/bash
# The replay's CPU by part (issue 15, session 11's budget): one replay under perf (samples of
# 0.1 ms of task-clock), grouped by thread and symbol into the engine's work on the analysis
# threads, the rest of the analysis threads, the decode thread's CRC / column fill / scan /
# begin (event) / kernel / other, the blocking threads' kernel time (the page-cache copy of the
# reads) and user time (the final fits), and the rest (start, writer).
# usage: benches/replay/parts.sh BIN      one replay of CAPTURE (as in ratio.sh)
#        benches/replay/parts.sh engine   the engine's functions in examples/stand_run alone
set -eu
capture=${CAPTURE:-/tmp/lab_siu8_3h.siu8}
engine=${ENGINE:-target/release/examples/stand_run}
d=$(mktemp)
load=$(cut -d' ' -f1 /proc/loadavg)
if [ "$1" = engine ]; then
  perf record -q -o "$d" -e task-clock -c 100000 "$engine" > /dev/null 2>&1
  perf report -i "$d" -n --no-children --sort symbol --stdio 2>/dev/null | grep -v "^#" \
    | awk -v load="$load" '/Engine.*process|second_differences|sum_sq|push_increments/{e+=$2}
      END{printf "load %s engine alone %d\n", load, e}'
  rm -f "$d"; exit 0
fi
perf record -q -o "$d" -e task-clock -c 100000 "$1" analyze "$capture" --format siu8 > /dev/null 2>&1
perf report -i "$d" -n --no-children --sort comm,dso,symbol --stdio 2>/dev/null | grep -v "^#" \
  | awk -v load="$load" '
NF>=5 {
  n=$2; comm=$3; sym=""; for(i=6;i<=NF;i++) sym=sym" "$i; all+=n
  if (comm=="allanscope-anal") {
    if (sym ~ /Engine.*process|second_differences|sum_sq|push_increments|Feeder::stretch/) eng+=n; else aoth+=n
  } else if (comm=="allanscope-deco") {
    if (sym ~ /checksums4|crc/) crc+=n
    else if (sym ~ /fill_columns/) fill+=n
    else if (sym ~ /Decoder::run|locked|scan|accept/) scan+=n
    else if (sym ~ /FramePlan::begin/) beg+=n
    else if ($5=="[k]") dk+=n
    else doth+=n
  } else if (comm=="tokio-rt-worker") {
    if ($5=="[k]") tk+=n; else tu+=n
  } else oth+=n
}
END { printf "load %s all %d | anal engine %d other %d | deco crc %d fill %d scan %d begin %d kernel %d other %d | blocking kernel %d user %d | rest %d\n", load, all, eng, aoth, crc, fill, scan, beg, dk, doth, tk, tu, oth }'
rm -f "$d"

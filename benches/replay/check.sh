#!/bin/bash
# Two binaries' replay records compared, elapsed_s masked (a change to the decoder must leave them
# byte-identical). usage, from the repository root: benches/replay/check.sh BIN_A BIN_B
# The damaged and simulated captures (siu8_dmg.siu8, siu8_20m.siu8, kvh_dmg.kvh1750, kvhb.kvh1750b,
# hg.hg4930) are made first in WORKDIR as BENCHMARKS.md (issue 15, session 9 and 10) says.
F=$(pwd)/fixtures/captures; W=${WORKDIR:-/tmp/replay-check}; mkdir -p "$W"; cd "$W"
run() { local bin=$1 tag=$2; shift 2; $bin "$@" 2>/dev/null | sed 's/"elapsed_s":[0-9.e-]*//' > out.$tag; }
ok=1
cmpset() { # name sorted?
  if [ "$2" = set ]; then diff <(sort out.A) <(sort out.B) >/dev/null; else cmp -s out.A out.B; fi
  r=$?; n=$(wc -l < out.A); [ $r = 0 ] && echo "same  $1 ($n lines)" || { echo "DIFF  $1"; ok=0; }
}
for spec in \
 "readme|exact|analyze $F/siu8_stand_5min_seed1.siu8 --format siu8" \
 "3h|exact|analyze /tmp/lab_siu8_3h.siu8 --format siu8" \
 "diag-clean|exact|analyze $F/siu8_stand_5min_seed1.siu8 --format siu8 --diagnose" \
 "diag-dmg|exact|analyze siu8_dmg.siu8 --format siu8 --diagnose" \
 "20m|exact|analyze siu8_20m.siu8 --format siu8" \
 "every60|set|analyze $F/siu8_stand_5min_seed1.siu8 --format siu8 --every 60" \
 "every30-dmg|set|analyze siu8_dmg.siu8 --format siu8 --every 30" \
 "kvh|set|analyze $F/kvh1750_stand_1min_seed1.kvh1750 --format kvh1750" \
 "kvh-dmg|set|analyze kvh_dmg.kvh1750 --format kvh1750 --diagnose" \
 "kvhb|set|analyze kvhb.kvh1750b --format kvh1750b --diagnose" \
 "hg|set|analyze hg.hg4930 --format hg4930 --diagnose" ; do
  IFS='|' read name mode args <<< "$spec"
  run $1 A $args; run $2 B $args; cmpset $name $mode
done
[ $ok = 1 ] && echo ALL SAME || echo SOME DIFFER

#!/bin/bash
# usage: runset.sh TAG BIN SET...   (SET names below); writes TAG_SET.{csv,txt,err} in $RUNS
# (default: the current folder) and a start/end line per set in runs.log. THREADS (default 1)
# sets family_gap's --threads. Session 12's runset.sh with session 14's accgrav family and the
# accfilt set of sessions 13-14 added.
TAG=$1; BIN=$2; shift 2
cd "${RUNS:-.}" || exit 1
D="--effects gauss_markov,sinusoid,output_filter,warmup,bias_jumps"
N="--effects none --no-oracle"
for S in "$@"; do
  case $S in
    agrav141) A="--families accgrav --hours 1,2 --seed 141 --draws 40 $N";;
    agrav151) A="--families accgrav --hours 1,2 --seed 151 --draws 40 $N";;
    acc107) A="--families accfilt --hours 1,2 --seed 107 --draws 40 $N";;
    u12c_a) A="--families cicacc,zpexp,bartfog --hours 1,2 --seed 121 --draws 20 $N";;
    u12c_k) A="--families kalgyro,kalacc --seed 121 --draws 20 $N";;
    u12c_k2) A="--families kalgyro,kalacc --seed 121 --draws 20 --from 20 $N";;
    u12d_k) A="--families kalgyro,kalacc --seed 123 --draws 3 $D";;
    p2_c132) A="--families navfog,tacfog,memsgyro,memsacc,ma4 --hours 1,1 --seed 132 --draws 10 $N";;
    p2_mimu) A="--families mimu --seed 132 --draws 10 $N";;
    p2_adis) A="--families adis --hours 1,2 --seed 132 --draws 10 $N";;
    *) echo "unknown set $S"; continue;;
  esac
  echo "$(date -u +%H:%M:%S) start $TAG $S: $A" >> runs.log
  $BIN $A --threads "${THREADS:-1}" --csv "${TAG}_$S.csv" > "${TAG}_$S.txt" 2> "${TAG}_$S.err"
  echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
done

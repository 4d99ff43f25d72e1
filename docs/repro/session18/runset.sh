#!/bin/bash
# usage: runset.sh TAG BIN SET...   (SET names below); writes TAG_SET.{csv,txt,err} in $RUNS
# (default: the current folder) and a start/end line per set in runs.log. THREADS (default 2).
# Session 18's proof table: seed 181 clean, seed 183 detection (plan.md).
TAG=$1; BIN=$2; shift 2
cd "${RUNS:-.}" || exit 1
D="--effects gauss_markov,sinusoid,output_filter,warmup,bias_jumps"
N="--effects none --no-oracle"
for S in "$@"; do
  case $S in
    c6) A="--families navfog,tacfog,vog4,memsgyro,ma4,memsacc --hours 1,1 --seed 181 --draws 100 $N";;
    d6) A="--families navfog,tacfog,vog4,memsgyro,ma4,memsacc --hours 1,2 --seed 183 --draws 20 $D";;
    ch) A="--families heldout --hours 1,1 --seed 181 --draws 10 $N";;
    cu9a) A="--families hrmems,short --seed 181 --draws 10 $N";;
    cu9b) A="--families qtzgyro,servoacc --hours 1,2 --seed 181 --draws 10 $N";;
    cu10) A="--families adis,adistemp,rlg,accfilt,navacc --hours 1,2 --seed 181 --draws 10 $N";;
    cu10l) A="--families lowrate --hours 1,3 --seed 181 --draws 10 $N";;
    cu11a) A="--families mimu,fog5k,thermfog --seed 181 --draws 10 $N";;
    cu11b) A="--families cicgyro,hrg --hours 1,2 --seed 181 --draws 10 $N";;
    cu12a) A="--families kalgyro,kalacc --seed 181 --draws 10 $N";;
    cu12b) A="--families cicacc,zpexp,bartfog,accgrav --hours 1,2 --seed 181 --draws 10 $N";;
    *) echo "unknown set $S"; continue;;
  esac
  echo "$(date -u +%H:%M:%S) start $TAG $S: $A" >> runs.log
  $BIN $A --threads "${THREADS:-2}" --csv "${TAG}_$S.csv" > "${TAG}_$S.txt" 2> "${TAG}_$S.err"
  echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
done

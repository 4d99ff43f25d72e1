#!/bin/bash
# Session 12, accq (docs/gap.md "Rounding after a filter (session 12)"): the run-for-run sets,
# once with main f372b34's family_gap and once with the wired branch's (commit 7047b21).
# usage: accq_runs.sh TAG BIN SET...  (CSV/txt/err as TAG_SET.* in $RUNS or here)
TAG=$1; BIN=$2; shift 2
cd "${RUNS:-.}"
for S in "$@"; do
  case $S in
    accf) A="--families accfilt --hours 1,2 --seed 107 --draws 40 --effects none --no-oracle";;
    accdet) A="--families accfilt --hours 1,2 --seed 128 --draws 3 --effects gauss_markov,sinusoid";;
    mems) A="--families memsacc,memsgyro --hours 1,1 --seed 82 --draws 10 --effects none --no-oracle";;
    mimu) A="--families mimu --seed 111 --draws 20 --effects none --no-oracle";;
    cic) A="--families cicgyro --hours 1,2 --seed 111 --draws 10 --effects none --no-oracle";;
    adis) A="--families adis --hours 1,2 --seed 107 --draws 20 --effects none --no-oracle";;
    cs) A="--families consmems,servoacc --hours 1,2 --seed 126 --draws 8 --effects none --no-oracle";;
    *) echo "unknown set $S"; continue;;
  esac
  echo "$(date -u +%H:%M:%S) start $TAG $S: $A" >> runs.log
  $BIN $A --threads 1 --csv ${TAG}_$S.csv > ${TAG}_$S.txt 2> ${TAG}_$S.err
  echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
done

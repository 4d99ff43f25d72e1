#!/bin/bash
# usage: runset.sh TAG BIN SET...   (SET names below); writes TAG_SET.{csv,txt,err} in $RUNS
# (default: the current folder) and a start/end line per set in runs.log.
# BIN: a build of examples/family_gap (e.g. target/release/examples/family_gap), copied aside
# per version so that a rebuild does not change a running set.
TAG=$1; BIN=$2; shift 2
cd "${RUNS:-.}" || exit 1
D="--effects gauss_markov,sinusoid,output_filter,warmup,bias_jumps"
for S in "$@"; do
  case $S in
    # session-12 families, clean (seed 121) and detection (seed 123)
    u12c_a) A="--families cicacc,zpexp,bartfog --hours 1,2 --seed 121 --draws 20 --effects none --no-oracle";;
    u12c_a2) A="--families cicacc,zpexp,bartfog --hours 1,2 --seed 121 --draws 20 --from 20 --effects none --no-oracle";;
    u12c_k) A="--families kalgyro,kalacc --seed 121 --draws 20 --effects none --no-oracle";;
    u12c_k2) A="--families kalgyro,kalacc --seed 121 --draws 20 --from 20 --effects none --no-oracle";;
    u12d_a) A="--families cicacc,zpexp,bartfog --hours 1,2 --seed 123 --draws 3 $D";;
    u12d_k) A="--families kalgyro,kalacc --seed 123 --draws 3 $D";;
    # the independent check's subsets of earlier families (fixed at 04:40 UTC)
    p2_acc) A="--families accfilt --hours 1,2 --seed 107 --draws 10 --effects none --no-oracle";;
    p2_fog5k) A="--families fog5k --seed 111 --draws 10 --effects none --no-oracle";;
    p2_short) A="--families short --seed 124 --draws 20 --effects none --no-oracle";;
    p2_c132) A="--families navfog,tacfog,memsgyro,memsacc,ma4 --hours 1,1 --seed 132 --draws 10 --effects none --no-oracle";;
    p2_mimu) A="--families mimu --seed 132 --draws 10 --effects none --no-oracle";;
    p2_adis) A="--families adis --hours 1,2 --seed 132 --draws 10 --effects none --no-oracle";;
    p2_w81) A="--families navfog,tacfog,memsgyro,memsacc,ma4,vog4 --hours 1,2 --seed 81 --draws 5 --effects warmup";;
    p2_w113) A="--families fog5k --seed 113 --draws 5 --effects warmup";;
    *) echo "unknown set $S"; continue;;
  esac
  echo "$(date -u +%H:%M:%S) start $TAG $S: $A" >> runs.log
  $BIN $A --threads 2 --csv "${TAG}_$S.csv" > "${TAG}_$S.txt" 2> "${TAG}_$S.err"
  echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
done

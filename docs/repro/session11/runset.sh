#!/bin/bash
# usage: runset.sh TAG BIN SET...   (SET names below); CSV/txt/err in /work/held3-runs/TAG_SET.*
TAG=$1; BIN=$2; shift 2
cd /work/held3-runs
for S in "$@"; do
  case $S in
    u11c) A="--families unseen11 --seed 111 --draws 40 --effects none --no-oracle";;
    u11c_a) A="--families mimu,fog5k,hrg --seed 111 --draws 40 --effects none --no-oracle";;
    u11c_b) A="--families cicgyro --hours 1,2 --seed 111 --draws 40 --effects none --no-oracle";;
    u11c_hrg) A="--families hrg --hours 1,2 --seed 111 --draws 40 --effects none --no-oracle";;
    u11c_mf) A="--families mimu,fog5k,thermfog --seed 111 --draws 40 --effects none --no-oracle";;
    u11d_a) A="--families mimu,fog5k,thermfog --seed 113 --draws 3 --effects gauss_markov,sinusoid,output_filter,warmup,bias_jumps";;
    u11d_b) A="--families cicgyro,hrg --hours 1,2 --seed 113 --draws 3 --effects gauss_markov,sinusoid,output_filter,warmup,bias_jumps";;
    short) A="--families short --seed 124 --draws 100 --effects none --no-oracle";;
    u10) A="--families adis,adistemp,rlg,accfilt,navacc --hours 1,2 --seed 127 --draws 40 --effects none --no-oracle";;
    u10low) A="--families lowrate --hours 1,3 --seed 127 --draws 40 --effects none --no-oracle";;
    u9h) A="--families hrmems --seed 125 --draws 20 --effects none --no-oracle";;
    u9) A="--families qtzgyro,servoacc --hours 1,2 --seed 125 --draws 20 --effects none --no-oracle";;
    held) A="--families heldout --hours 1,1 --seed 126 --draws 20 --effects none --no-oracle";;
    d128a) A="--families adis,accfilt --hours 1,2 --seed 128 --draws 3 --effects sinusoid,gauss_markov";;
    d128b) A="--families hrmems --seed 128 --draws 3 --effects moving_average";;
    d128c) A="--families ma4 --hours 1,2 --seed 128 --draws 3 --effects gauss_markov";;
    d128d) A="--families tacfog --hours 1,2 --seed 128 --draws 3 --effects warmup";;
    d128e) A="--families memsgyro --hours 1,2 --seed 128 --draws 3 --effects bias_jumps";;
    r_short) A="--families short --seed 124 --draws 50 --effects none --no-oracle";;
    r_u10) A="--families adis,adistemp,accfilt,rlg --hours 1,2 --seed 127 --draws 10 --effects none --no-oracle";;
    r_u10b) A="--families navacc --hours 1,2 --seed 127 --draws 5 --effects none --no-oracle";;
    r_u10low) A="--families lowrate --hours 1,3 --seed 127 --draws 5 --effects none --no-oracle";;
    r_u9h) A="--families hrmems --seed 125 --draws 5 --effects none --no-oracle";;
    r_u9) A="--families qtzgyro,servoacc --hours 1,2 --seed 125 --draws 5 --effects none --no-oracle";;
    r_held) A="--families heldout --hours 1,1 --seed 126 --draws 5 --effects none --no-oracle";;
    f_mimu) A="--families mimu --seed 111 --draws 20 --effects none --no-oracle";;
    f_cic) A="--families cicgyro --hours 1,2 --seed 111 --draws 10 --effects none --no-oracle";;
    f_hrg) A="--families hrg --hours 1,2 --seed 111 --draws 10 --effects none --no-oracle";;
    f_tf) A="--families thermfog,fog5k --seed 111 --draws 10 --effects none --no-oracle";;
    *) echo "unknown set $S"; continue;;
  esac
  echo "$(date -u +%H:%M:%S) start $TAG $S: $A" >> runs.log
  $BIN $A --threads 2 --csv ${TAG}_$S.csv > ${TAG}_$S.txt 2> ${TAG}_$S.err
  echo "$(date -u +%H:%M:%S) end $TAG $S rc=$?" >> runs.log
done

#!/bin/bash
# held2 s10 item 2: fresh seeds fixed at 22:41 UTC. $1 = family_gap binary, $2 = tag (base | final).
# Part 1 (draws 0-19 / short 0-99), part 2 (draws 20-39) only if asked ($3 = 2).
cd "${RUNS:-.}"
B=$1; T=$2; P=${3:-1}
run() { local name=$1; shift; [ -s ${T}_$name.csv ] || $B "$@" --csv ${T}_$name.csv > ${T}_$name.txt 2> ${T}_$name.err; }
if [ $P = 1 ]; then
run short104 --draws 100 --seed 104 --threads 2 --effects none --no-oracle --families short
for f in adis adistemp accfilt; do run ${f}107 --draws 20 --hours 1,2 --seed 107 --threads 2 --effects none --no-oracle --families $f; done
run hrmems108 --draws 3 --seed 108 --threads 2 --effects moving_average --shares 1,1,1,1,1 --families hrmems
for f in accfilt adis; do run ${f}108 --draws 3 --hours 1,2 --seed 108 --threads 2 --effects gauss_markov,sinusoid --shares 1,1,1,1,1 --families $f; done
for f in hrmems qtzgyro servoacc; do run ${f}105 --draws 20 --seed 105 --threads 2 --effects none --no-oracle --families $f; done
for f in rlg navacc; do run ${f}107 --draws 20 --hours 1,2 --seed 107 --threads 2 --effects none --no-oracle --families $f; done
run lowrate107 --draws 20 --hours 1,3 --seed 107 --threads 2 --effects none --no-oracle --families lowrate
run held106 --draws 20 --hours 1,1 --seed 106 --threads 2 --effects none --no-oracle --families heldout
run long105 --draws 10 --seed 105 --threads 2 --effects none --no-oracle --families long
else
for f in accfilt adis adistemp; do run ${f}107b --draws 20 --from 20 --hours 1,2 --seed 107 --threads 2 --effects none --no-oracle --families $f; done
run held106b --draws 20 --from 20 --hours 1,1 --seed 106 --threads 2 --effects none --no-oracle --families heldout
for f in hrmems qtzgyro servoacc; do run ${f}105b --draws 20 --from 20 --seed 105 --threads 2 --effects none --no-oracle --families $f; done
fi
echo done > run_b_${T}_$P.done

#!/bin/bash
# Draws 10-39 of seed 181 for the 26 other families (after the plan's draws 0-9), in two
# queues (more_draws.sh a & more_draws.sh b); the held-out five and kalgyro/kalacc ran the same
# way before them:
#   family_gap --families heldout --hours 1,1 $N; family_gap --families kalgyro,kalacc $N
# B is the release build of examples/family_gap.
B=${B:-target/release/examples/family_gap}
N="--effects none --no-oracle --seed 181 --draws 30 --from 10 --threads 1"
case $1 in
 a) $B --families cicacc,zpexp,bartfog,accgrav --hours 1,2 $N --csv m_cu12b.csv > m_cu12b.txt 2>&1
    $B --families mimu,fog5k,thermfog $N --csv m_cu11a.csv > m_cu11a.txt 2>&1
    $B --families hrmems,short $N --csv m_cu9a.csv > m_cu9a.txt 2>&1
    echo done > m_done_a;;
 b) $B --families adis,adistemp,rlg,accfilt,navacc --hours 1,2 $N --csv m_cu10.csv > m_cu10.txt 2>&1
    $B --families cicgyro,hrg --hours 1,2 $N --csv m_cu11b.csv > m_cu11b.txt 2>&1
    $B --families qtzgyro,servoacc --hours 1,2 $N --csv m_cu9b.csv > m_cu9b.txt 2>&1
    $B --families lowrate --hours 1,3 $N --csv m_cu10l.csv > m_cu10l.txt 2>&1
    echo done > m_done_b;;
esac

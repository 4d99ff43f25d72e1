#!/bin/bash
# The warm-up's null with K^2 profiled on the block means (docs/gap.md, "The warm-up's null
# level (session 12)"): every run of its run-for-run table.
# usage: warm5_runs.sh TAG BIN   (BIN: a build of examples/family_gap at the commit measured,
# copied aside; writes TAG_SET.{csv,txt} in the current folder).
# Compare two tags' CSVs row by row on (family, effect, draw): verdict, named, gap_after,
# false_alarm; the CSV's last four columns (warm_p_up, warm_p_prof, warm_k_up, warm_k_null)
# exist only in builds from session 12 on.
TAG=$1; BIN=$2
r() { S=$1; shift; "$BIN" --threads 1 "$@" --csv "${TAG}_$S.csv" > "${TAG}_$S.txt" 2>&1; }
r fog5k_w113 --families fog5k --effects warmup --seed 113 --draws 10
r short_w113 --families short --effects warmup --seed 113 --draws 10
r nt_w81 --families navfog,tacfog --effects warmup --seed 81 --hours 1,2 --draws 10
r fog5k_n111 --families fog5k --effects none --no-oracle --seed 111 --draws 40
r short_n124 --families short --effects none --no-oracle --seed 124 --draws 50
r c82 --families navfog,tacfog,memsgyro,memsacc,ma4 --effects none --no-oracle --seed 82 --hours 1,1 --draws 20
r c82b --families navfog,tacfog,memsgyro,memsacc,ma4 --effects none --no-oracle --seed 82 --hours 1,1 --draws 20 --from 20
r adis_n82 --families adistemp --effects none --no-oracle --seed 82 --hours 1,2 --draws 10
r therm_n82 --families thermfog --effects none --no-oracle --seed 82 --draws 5
r zp121 --families zpexp --effects none --no-oracle --seed 121 --draws 20
r zph --families zpexp --effects none --no-oracle --seed 121 --hours 1,2 --draws 40

#!/bin/bash
# usage: run.sh BIN TAG ; runs the line-behind-filter matrix
BIN=$1; TAG=$2
for filt in "ma2:moving_average = { taps = 2, stages = 1 }" "ma4:moving_average = { taps = 4, stages = 1 }" "fo3:output_filter = { time_constant = 0.03 }"; do
 fname=${filt%%:*}; ftxt=${filt#*:}
 for f in 3 5 12 20; do
  for seed in 1 2 3; do
   m=${fname}_f${f}_s${seed}
   if [ ! -f $m.csv ]; then
    printf 'tau0_s = 0.01\n[[channel]]\nname = "g"\nunit = "deg"\nN = 0.04\nB = 0.007\nsinusoid = { amplitude = 0.3, frequency = %s, phase = 0.3 }\n%s\n' $f "$ftxt" > $m.toml
    $BIN simulate --model $m.toml --duration 1h --seed $((10100+seed)) --format csv -o $m.csv --force >/dev/null 2>&1
   fi
   $BIN diagnose $m.csv --tau0 0.01 --unit deg 2>/dev/null | python3 -c "
import json,sys
for l in sys.stdin:
  r=json.loads(l)
  if r.get('type')=='diagnosis': print('$m', r['verdict'], round(r['gap_before'],1), round(r['gap_after'],2), ' '.join(e['kind']+':'+','.join('%s=%.4g'%(k,v) for k,v in e['params'].items()) for e in r['effects']))
"
  done
 done
done > res_$TAG.txt

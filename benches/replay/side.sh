#!/bin/bash
# Per-thread samples of several binaries' replays, interleaved round by round; medians and ranges.
# usage: benches/replay/side.sh ROUNDS BIN1 BIN2 ...
set -eu
rounds=$1; shift
here=$(dirname "$0")
out=$(mktemp)
for _ in $(seq "$rounds"); do for b in "$@"; do "$here/threads.sh" "$b" >> "$out"; done; done
for b in "$@"; do
  for col in total anal deco tokio; do
    vals=$(awk -v b="$b" -v c=$col '$1==b{for(i=2;i<NF;i++) if($i==c) print $(i+1)}' "$out" | sort -n | tr '\n' ' ')
    n=$(echo $vals | wc -w); med=$(echo $vals | tr ' ' '\n' | sed -n "$(( (n+1)/2 ))p")
    echo "$b $col median $med  [$(echo $vals | awk '{print $1"-"$NF}')]"
  done
done
rm -f "$out"

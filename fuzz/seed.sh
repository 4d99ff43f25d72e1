#!/usr/bin/env bash
# Builds the starting corpus of every fuzz target (fuzz/corpus/TARGET/) from what the project
# ships: captures, descriptors, text fixtures, configs and model files, and checkpoints written
# by the binary. Run from the crate's root after `cargo build --release`; see fuzz/README.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/allanscope
[ -x "$bin" ] || { echo "build the binary first: cargo build --release" >&2; exit 1; }
c=fuzz/corpus
rm -rf "$c" && mkdir -p "$c"/{frames,descriptor,checkpoint,text,configs}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# Frames: the heads of the shipped captures (8 KiB: the default -max_len is 4 KiB, longer
# seeds are cut by libFuzzer), and a simulated hg4930 capture (no fixture ships one).
for f in fixtures/captures/*.siu8 fixtures/captures/*.kvh1750; do
  head -c 8192 "$f" > "$c/frames/$(basename "$f")"
done
"$bin" simulate --model config/models/siu8_stand.toml --duration 1 --format hg4930 \
  -o "$tmp/cap.hg4930" 2>/dev/null && head -c 8192 "$tmp/cap.hg4930" > "$c/frames/sim.hg4930"
"$bin" simulate --model config/models/kvh1750_stand.toml --duration 1 --format kvh1750b \
  -o "$tmp/cap.kvh1750b" 2>/dev/null && head -c 8192 "$tmp/cap.kvh1750b" > "$c/frames/sim.kvh1750b"

# Descriptors.
cp config/frames/*.toml "$c/descriptor/"

# Text columns.
head -c 4096 fixtures/captures/vog4_2min_seed7.csv > "$c/text/vog4.csv"
for f in fixtures/nbs14/*.txt; do cp "$f" "$c/text/"; done
printf 'time;g1;g2\n0;1,5;2\n1;;3\n2;x;4\n3;inf;5\n' > "$c/text/semicolons.csv"

# Configs: stand configs, model files, a limits file.
cp config/stand.toml "$c/configs/stand.toml"
for f in config/models/*.toml; do cp "$f" "$c/configs/model_$(basename "$f")"; done
printf '[[limits]]\nchannel = "g*"\ncoef = "N"\nmax = 0.3\nunit = "arcsec/sqrt(s)"\n' \
  > "$c/configs/limits.toml"

# Checkpoints (their bodies: the target adds the header and CRC): text with the diagnosis,
# and siu8 frames, each written by a run stopped part way.
printf 'g1,g2\n' > "$tmp/in.csv"
awk 'BEGIN { for (i = 0; i < 3000; i++) printf "%g,%g\n", (i * 7919 % 101) * 0.01, i % 13 }' \
  >> "$tmp/in.csv"
cp fixtures/captures/siu8_stand_5min_seed1.siu8 "$tmp/cap.siu8"
(cd "$tmp" && ALLANSCOPE_LOG=off "$OLDPWD/$bin" analyze in.csv --tau0 0.01 --diagnose \
  --fit none --out t.jsonl --checkpoint-every 1 --abort-after-frames 1000 >/dev/null 2>&1 || true)
(cd "$tmp" && ALLANSCOPE_LOG=off "$OLDPWD/$bin" analyze cap.siu8 --format siu8 --fit none \
  --out f.jsonl --checkpoint-every 1 --abort-after-frames 1000 >/dev/null 2>&1 || true)
for k in t f; do
  [ -f "$tmp/$k.jsonl.ckpt" ] && tail -c +33 "$tmp/$k.jsonl.ckpt" > "$c/checkpoint/$k.cbor"
done
ls -l "$c"/*

#!/usr/bin/env python3
"""Runs two allanscope binaries on every input file of the given folders and says, per file,
whether the exit status and the final curve records (channel, statistic, unit, tau, sigma to
12 digits, counts) are the same.

usage: compare_records.py OLD_BIN NEW_BIN DIR...   (session 34: the review folders' 260 files)
"""
import glob
import json
import os
import subprocess
import sys
import tempfile

SKIP = (".jsonl", ".py", ".json", ".err", ".log", ".ckpt", ".sh", ".md")


def run(binary, path, out):
    if os.path.exists(out):
        os.remove(out)
    try:
        p = subprocess.run([binary, "analyze", path, "--out", out, "--force", "--fit", "none"],
                           capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return "timeout", None
    curves = {}
    if os.path.exists(out):
        for line in open(out):
            try:
                r = json.loads(line)
            except ValueError:
                continue
            if r.get("type") == "curve" and r.get("final"):
                curves[(r["channel"], r["stat"])] = (
                    r["unit"], r["tau"], [round(s, 12) for s in r["sigma"]], r["count"])
    return p.returncode, curves


def main():
    old, new, dirs = sys.argv[1], sys.argv[2], sys.argv[3:]
    files = [f for d in dirs for f in sorted(glob.glob(os.path.join(d, "*")))
             if os.path.isfile(f) and not f.endswith(SKIP) and os.path.getsize(f) < 30_000_000]
    tmp = tempfile.mkdtemp()
    same = 0
    for f in files:
        (ro, co) = run(old, f, os.path.join(tmp, "old.jsonl"))
        (rn, cn) = run(new, f, os.path.join(tmp, "new.jsonl"))
        if ro == rn and co == cn:
            same += 1
            continue
        names = lambda c: sorted({k[0] for k in (c or {})})
        units = lambda c: sorted({v[0] for v in (c or {}).values()})
        print(f"DIFF {f}: exit {ro} -> {rn}; channels {names(co)} -> {names(cn)}; "
              f"units {units(co)} -> {units(cn)}")
    print(f"{len(files)} files: {same} the same, {len(files) - same} differ")


if __name__ == "__main__":
    main()

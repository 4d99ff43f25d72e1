#!/usr/bin/env python3
"""The share of clean runs each test of the diagnosis spends, per family and pooled, read off a
family_gap CSV of clean runs (docs/gap.md, "Detection against the oracle"): a stationary
candidate fires when G > gap_crit or its own likelihood ratio lr / max(1, G_alt) > lr_crit; the
warm-up when a warm-up is named; the jump rule on the first pass of the step search.
usage: shares.py CLEAN.csv"""
import csv, sys
GAP_CRIT, LR = 1.9, {"gm": 5.5, "sin": 7.0, "filter": 7.0}
JUMP_Z = (4.5, 4.0, 3.4)
rows = list(csv.DictReader(open(sys.argv[1])))
fams = sorted({r["family"] for r in rows}, key=[r["family"] for r in rows].index)
def f(x):
    try:
        return float(x)
    except ValueError:
        return float("nan")
def fires(r):
    g = f(r["gap_before"]) > GAP_CRIT
    out = {}
    for k, c in LR.items():
        lr, ga = f(r["lr_" + k]), f(r["galt_" + k])
        out[k] = g or (lr / max(1.0, ga) > c if ga == ga else lr > c)
    out["warmup"] = "warmup" in r["named"].split("+")
    z = [f(r["jump_z%d" % i]) for i in (1, 2, 3)]
    out["jumps"] = any(z[i] >= JUMP_Z[i] for i in range(3))
    return out
keys = ["gm", "sin", "filter", "warmup", "jumps"]
print("| family | n | " + " | ".join(keys) + " |")
print("|---|---|" + "---|" * len(keys))
for fam in fams + ["all"]:
    rs = [r for r in rows if fam == "all" or r["family"] == fam]
    fs = [fires(r) for r in rs]
    cells = ["%d (%.1f%%)" % (sum(x[k] for x in fs), 100.0 * sum(x[k] for x in fs) / len(fs)) for k in keys]
    print("| %s | %d | %s |" % (fam, len(rs), " | ".join(cells)))

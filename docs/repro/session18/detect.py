#!/usr/bin/env python3
"""The detection table of docs/gap.md ("Detection against the oracle") read off a family_gap CSV
of effect draws at a share A (default 1%): per family and effect, the true effect named / draws,
the oracle's expected power mean Phi(delta - z_(1-A)) [draws whose oracle z passes], the
difference in points; for the jump draws the fair jump ceiling (p <= A) and the draws where the
jump rule fired on the first pass of the step search (found in time, whether kept or not; at
the base fit's terms; in session 28's CSVs the procedure's `jump_excess` against its
`jump_shift`).
usage: detect.py DETECT.csv [A]"""
import csv, sys
from statistics import NormalDist
A = float(sys.argv[2]) if len(sys.argv) > 2 else 0.01
ND = NormalDist()
za = ND.inv_cdf(1 - A)
rows = list(csv.DictReader(open(sys.argv[1])))
fams = sorted({r["family"] for r in rows}, key=[r["family"] for r in rows].index)
kinds = ["gauss_markov", "sinusoid", "output_filter", "warmup", "bias_jumps"]
JUMP_Z = (4.5, 4.0, 3.4)
def f(x):
    try:
        return float(x)
    except ValueError:
        return float("nan")
tot = {k: [0, 0, 0.0, 0] for k in kinds}
jt = [0, 0, 0, 0]
print("| family | " + " | ".join(kinds) + " | jumps: fair ceiling / found in time / named |")
print("|---|" + "---|" * (len(kinds) + 1))
for fam in fams:
    cells = []
    for k in kinds:
        rs = [r for r in rows if r["family"] == fam and r["effect"] == k]
        if not rs:
            cells.append("-")
            continue
        named = sum(k in r["named"].split("+") for r in rs)
        d = [f(r["oracle_delta"]) for r in rs]
        pw = sum(ND.cdf(x - za) for x in d if x == x) / len(rs)
        zp = sum(f(r["oracle_z"]) > za for r in rs)
        cells.append("%d/%d vs %.0f%% [%d] (%+.0f)" % (named, len(rs), 100 * pw, zp, 100 * (named / len(rs) - pw)))
        t = tot[k]
        t[0] += named; t[1] += len(rs); t[2] += pw * len(rs); t[3] += zp
    rs = [r for r in rows if r["family"] == fam and r["effect"] == "bias_jumps"]
    ceil = sum(f(r["jceil_p"]) <= A + 1e-12 for r in rs)
    # session 28's CSVs: the jump procedure's own excess and shift at the base fit's terms
    def fired(r):
        if r.get("jump_excess", "") not in ("", "NaN", "nan"):
            return f(r["jump_excess"]) >= f(r["jump_shift"])
        return any(f(r["jump_z%d" % (i + 1)]) >= JUMP_Z[i] for i in range(3))
    found = sum(fired(r) for r in rs)
    named = sum("bias_jumps" in r["named"].split("+") for r in rs)
    jt[0] += ceil; jt[1] += found; jt[2] += named; jt[3] += len(rs)
    cells.append("%d / %d / %d of %d" % (ceil, found, named, len(rs)))
    print("| %s | %s |" % (fam, " | ".join(cells)))
cells = []
for k in kinds:
    t = tot[k]
    if not t[1]:
        cells.append("-")
        continue
    cells.append("%d/%d vs %.0f%% [%d] (%+.0f)" % (t[0], t[1], 100 * t[2] / t[1], t[3], 100 * (t[0] - t[2]) / t[1]))
cells.append("%d / %d / %d of %d" % tuple(jt))
print("| all | %s |" % " | ".join(cells))

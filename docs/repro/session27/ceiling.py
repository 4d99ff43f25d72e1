#!/usr/bin/env python3
"""Detection against the fair shape ceiling (docs/gap.md, "Fair ceilings of the stationary
effects and the warm-up (session 27)"), read off family_gap CSVs: per family and effect
(Gauss-Markov, sinusoid, output filter, warm-up), the true effect named (in brackets: the
further draws where it is only listed among the record's alternatives, `alt_kinds`) / draws, the ceiling's
count at the share A (`cceil_p <= A`: told the kind and rho, not the shape), the oracle's count
at A (`oracle_z > z_(1-A)`: told everything) and its expected power. Clean rows (effect `none`,
run without --no-oracle) give the ceilings' own levels: the share of clean runs with
`cceil_p <= A` at the null stream's Gauss-Markov draw and `wceil_p <= A` at its warm-up draw. With --share S the ceiling and the oracle are also read
at S (the diagnosis's own share, say).
usage: ceiling.py CSV... [--a A] [--share S]"""
import csv, sys
from statistics import NormalDist
args = sys.argv[1:]
def opt(name, default):
    if name in args:
        i = args.index(name)
        v = float(args[i + 1])
        del args[i:i + 2]
        return v
    return default
A = opt("--a", 0.01)
S = opt("--share", float("nan"))
ND = NormalDist()
rows = [r for p in args for r in csv.DictReader(open(p))]
def f(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")
kinds = ["gauss_markov", "sinusoid", "output_filter", "warmup"]
fams = list(dict.fromkeys(r["family"] for r in rows))
def cell(rs, k, a):
    za = ND.inv_cdf(1 - a)
    named = sum(k in r["named"].split("+") for r in rs)
    listed = sum(k not in r["named"].split("+") and k in r.get("alt_kinds", "").split("+") for r in rs)
    ceil = sum(f(r["cceil_p"]) <= a for r in rs)
    orc = sum(f(r["oracle_z"]) > za for r in rs)
    pw = sum(ND.cdf(f(r["oracle_delta"]) - za) for r in rs) / len(rs)
    return named, listed, ceil, orc, pw
levels = [A] + ([S] if S == S else [])
head = ["family"] + ["%s at %g%%: named (+listed) / ceiling / oracle [expected]" % (k, 100 * a) for a in levels for k in kinds]
print("| " + " | ".join(head) + " | clean: GM / warm-up ceiling at %g%% |" % (100 * A))
print("|---" * (len(head) + 1) + "|")
tot = {}
for fam in fams:
    cells = []
    for a in levels:
        for k in kinds:
            rs = [r for r in rows if r["family"] == fam and r["effect"] == k]
            if not rs:
                cells.append("-")
                continue
            n, l, c, o, pw = cell(rs, k, a)
            t = tot.setdefault((a, k), [0, 0, 0, 0, 0.0, 0])
            t[0] += n; t[1] += l; t[2] += c; t[3] += o; t[4] += pw * len(rs); t[5] += len(rs)
            cells.append("%d (+%d) / %d / %d [%.0f%%] of %d" % (n, l, c, o, 100 * pw, len(rs)))
    cl = [r for r in rows if r["family"] == fam and r["effect"] == "none" and f(r["cceil_p"]) == f(r["cceil_p"])]
    g = sum(f(r["cceil_p"]) <= A for r in cl)
    w = sum(f(r.get("wceil_p")) <= A for r in cl)
    t = tot.setdefault("clean", [0, 0, 0])
    t[0] += g; t[1] += w; t[2] += len(cl)
    cells.append("%d / %d of %d" % (g, w, len(cl)) if cl else "-")
    print("| %s | %s |" % (fam, " | ".join(cells)))
cells = []
for a in levels:
    for k in kinds:
        t = tot.get((a, k))
        cells.append("%d (+%d) / %d / %d [%.0f%%] of %d" % (t[0], t[1], t[2], t[3], 100 * t[4] / t[5], t[5]) if t else "-")
t = tot.get("clean", [0, 0, 0])
cells.append("%d / %d of %d" % tuple(t) if t[2] else "-")
print("| all | %s |" % " | ".join(cells))

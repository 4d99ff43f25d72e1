#!/usr/bin/env python3
"""The stationary effects' detection against the fair curve ceiling (docs/gap.md, "The
Gauss-Markov ceiling (session 27)"), read off family_gap CSVs: per family and effect
(Gauss-Markov, sinusoid, output filter), the true effect named / draws, the ceiling's count at
the share A (`cceil_p <= A`: told the kind and rho, not the shape), the oracle's count at A
(`oracle_z > z_(1-A)`: told everything) and its expected power. Clean rows (effect `none`, run
without --no-oracle) give the ceiling's own level: the share of clean runs with `cceil_p <= A`
at the null stream's Gauss-Markov draw. With --share S the ceiling and the oracle are also read
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
kinds = ["gauss_markov", "sinusoid", "output_filter"]
fams = list(dict.fromkeys(r["family"] for r in rows))
def cell(rs, k, a):
    za = ND.inv_cdf(1 - a)
    named = sum(k in r["named"].split("+") for r in rs)
    ceil = sum(f(r["cceil_p"]) <= a for r in rs)
    orc = sum(f(r["oracle_z"]) > za for r in rs)
    pw = sum(ND.cdf(f(r["oracle_delta"]) - za) for r in rs) / len(rs)
    return named, ceil, orc, pw
levels = [A] + ([S] if S == S else [])
head = ["family"] + ["%s at %g%%: named / ceiling / oracle [expected]" % (k, 100 * a) for a in levels for k in kinds]
print("| " + " | ".join(head) + " | clean: ceiling at %g%% |" % (100 * A))
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
            n, c, o, pw = cell(rs, k, a)
            t = tot.setdefault((a, k), [0, 0, 0, 0.0, 0])
            t[0] += n; t[1] += c; t[2] += o; t[3] += pw * len(rs); t[4] += len(rs)
            cells.append("%d / %d / %d [%.0f%%] of %d" % (n, c, o, 100 * pw, len(rs)))
    cl = [r for r in rows if r["family"] == fam and r["effect"] == "none" and f(r["cceil_p"]) == f(r["cceil_p"])]
    t = tot.setdefault("clean", [0, 0])
    t[0] += sum(f(r["cceil_p"]) <= A for r in cl); t[1] += len(cl)
    cells.append("%d/%d" % (sum(f(r["cceil_p"]) <= A for r in cl), len(cl)) if cl else "-")
    print("| %s | %s |" % (fam, " | ".join(cells)))
cells = []
for a in levels:
    for k in kinds:
        t = tot.get((a, k))
        cells.append("%d / %d / %d [%.0f%%] of %d" % (t[0], t[1], t[2], 100 * t[3] / t[4], t[4]) if t else "-")
t = tot.get("clean", [0, 0])
cells.append("%d/%d" % tuple(t) if t[1] else "-")
print("| all | %s |" % " | ".join(cells))

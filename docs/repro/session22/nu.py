#!/usr/bin/env python3
"""The base G of clean runs against chi2_nu / nu (session 22).

usage: nu.py CSV...   (family_gap --csv files with the columns nu and n_taus)
Per family, split by quantization_limited: runs, the median and range of nu, the median number
of taus, G's median and 95% point, the runs with G > 1.9 and those whose G nu lies beyond the
chi2_nu 1% and 3% upper points.
"""
import csv
import math
import sys
from statistics import median


def chi2_sf(x, k):
    """Upper tail of chi-square with k degrees of freedom: Q(k/2, x/2), by the series of the
    lower incomplete gamma below a + 1 and the Lentz continued fraction above
    (Numerical Recipes 3rd ed., section 6.2)."""
    a, z = k / 2.0, x / 2.0
    if z <= 0:
        return 1.0
    lead = math.exp(-z + a * math.log(z) - math.lgamma(a))
    if z < a + 1:
        term = total = 1.0 / a
        n = a
        while abs(term) > abs(total) * 1e-15:
            n += 1
            term *= z / n
            total += term
        return 1.0 - total * lead
    b = z + 1 - a
    c, d = 1e300, 1.0 / b
    h = d
    for i in range(1, 10000):
        an = -i * (i - a)
        b += 2
        d = an * d + b
        d = 1.0 / (d if abs(d) > 1e-300 else 1e-300)
        c = b + an / c
        if abs(c) < 1e-300:
            c = 1e-300
        h *= d * c
        if abs(d * c - 1) < 1e-15:
            break
    return lead * h


rows = [r for f in sys.argv[1:] for r in csv.DictReader(open(f))]
rows = [r for r in rows if r["gap_before"] not in ("NaN", "") and r["nu"] not in ("NaN", "")]
fams = sorted({r["family"] for r in rows})
print("| family | quantization-limited | runs | nu median [range] | taus | G median / q95 | G > 1.9 | chi2_nu p < 0.01 | p < 0.03 |")
print("|---|---|---|---|---|---|---|---|---|")
for fam in fams + ["all"]:
    for q in ("true", "false"):
        sub = [r for r in rows if (fam == "all" or r["family"] == fam) and r["qlim"] == q]
        if not sub:
            continue
        nus = [float(r["nu"]) for r in sub]
        g = sorted(float(r["gap_before"]) for r in sub)
        p = [chi2_sf(float(r["gap_before"]) * float(r["nu"]), float(r["nu"])) for r in sub]
        taus = median(int(r["n_taus"]) for r in sub)
        q95 = g[max(0, math.ceil(0.95 * len(g)) - 1)]
        print(f"| {fam} | {q} | {len(sub)} | {median(nus):.1f} [{min(nus):.1f}, {max(nus):.1f}] | {taus:.0f} | "
              f"{median(g):.2f} / {q95:.2f} | {sum(x > 1.9 for x in g)} | {sum(x < 0.01 for x in p)} | {sum(x < 0.03 for x in p)} |")

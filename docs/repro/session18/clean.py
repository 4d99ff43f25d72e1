#!/usr/bin/env python3
"""Clean runs per family from family_gap CSVs: false alarms (the harness's own per-family rule,
column false_alarm) with 95% Wilson intervals, what was named on them, base G median / q95, and
the runs whose final gap is above the base gap. usage: clean.py CSV..."""
import csv, sys, math
def wilson(k, n, z=1.96):
    p = k / n; d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d; h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0, c - h), min(1, c + h)
def q(v, p):
    v = sorted(v); i = p * (len(v) - 1); lo = int(math.floor(i)); hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (i - lo)
rows = [r for fn in sys.argv[1:] for r in csv.DictReader(open(fn)) if r["effect"] == "none"]
fams = sorted({r["family"] for r in rows}, key=[r["family"] for r in rows].index)
print("| family | flagged (95% Wilson) | named on the flagged runs (draw) | G0 median / q95 | final > base |")
print("|---|---|---|---|---|")
tk = tn = 0
for fam in fams:
    rs = [r for r in rows if r["family"] == fam]
    fa = [r for r in rs if r["false_alarm"] == "true"]
    lo, hi = wilson(len(fa), len(rs))
    g0 = [float(r["gap_before"]) for r in rs]
    worse = sum(float(r["gap_after"]) > float(r["gap_before"]) * (1 + 1e-12) for r in rs)
    what = ", ".join("%s (%s)" % (r["named"] or r["verdict"] + " G %.2f" % float(r["gap_before"]), r["draw"]) for r in fa)
    print("| %s | %d/%d (%.0f%%; %.0f-%.0f%%) | %s | %.2f / %.2f | %d |" % (fam, len(fa), len(rs), 100 * len(fa) / len(rs), 100 * lo, 100 * hi, what or "-", q(g0, .5), q(g0, .95), worse))
    tk += len(fa); tn += len(rs)
lo, hi = wilson(tk, tn)
print("| all | %d/%d (%.1f%%; %.1f-%.1f%%) | | | |" % (tk, tn, 100 * tk / tn, 100 * lo, 100 * hi))

#!/usr/bin/env python3
"""Side-by-side summary: σ_top at given strains for tomograin (history.csv)
and LIGGGHTS (stress_strain_*.txt), plus throughput lines from the logs.
Usage: compare.py tomograin_history.csv liggghts_stress_strain.txt"""
import sys

def table(path, sep=None):
    lines = [l for l in open(path) if l.strip()]
    head = lines[0].replace(",", " ").split()
    rows = [[float(x) for x in l.replace(",", " ").split()] for l in lines[1:]]
    return {h: [r[i] for r in rows] for i, h in enumerate(head)}

def at(xs, ys, x):
    for i in range(1, len(xs)):
        if xs[i] >= x:
            t = (x - xs[i - 1]) / (xs[i] - xs[i - 1]) if xs[i] != xs[i - 1] else 0
            return ys[i - 1] + t * (ys[i] - ys[i - 1])
    return float("nan")

tg = table(sys.argv[1])
lg = table(sys.argv[2])
print("strain  sigma_top_tomograin_MPa  sigma_top_liggghts_MPa  diff_%")
for e in (0.02, 0.04, 0.06, 0.08, 0.10):
    a = at(tg["strain"], tg["top_stress_Pa"], e) / 1e6
    b = at(lg["strain"], lg["sigma_top_Pa"], e) / 1e6
    print("%.2f    %10.4f               %10.4f             %6.1f" % (e, a, b, 100 * (a - b) / b if b else float("nan")))

#!/usr/bin/python3
"""Figures of a `tomograin dem calibrate` folder: DIR/objective_surface.png.

Left: the Gaussian-process surrogate's mean objective over the two
parameters (surface.csv), every run as a numbered dot (runs.csv), the best
run as a star and the surrogate's predicted optimum as a cross.
Right: the target stress-strain curve against every run's (history.csv), the
best run highlighted. Usage: plot_calibration.py DIR (Debian's python3-matplotlib).
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [r[k] for r in rows] for k in (rows[0].keys() if rows else [])}


def num(col):
    return np.array([float(x) for x in col])


def main(d):
    meta = json.load(open(os.path.join(d, "calibration.json")))
    p0, p1 = (p["name"] for p in meta["parameters"])
    s = read_csv(os.path.join(d, "surface.csv"))
    runs = read_csv(os.path.join(d, "runs.csv"))
    a, b, m = num(s[p0]), num(s[p1]), num(s["objective_mean"])
    n = int(round(np.sqrt(len(a))))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5))
    cs = ax.contourf(a.reshape(n, n), b.reshape(n, n), m.reshape(n, n), levels=20, cmap="viridis")
    fig.colorbar(cs, ax=ax, label="surrogate mean objective")
    x, y, j = num(runs[p0]), num(runs[p1]), num(runs["objective"])
    ax.scatter(x, y, c="white", edgecolors="black", s=25, zorder=3)
    for i in range(len(x)):
        ax.annotate(str(i), (x[i], y[i]), textcoords="offset points", xytext=(4, 3), fontsize=7, color="white")
    best = meta["best"]["parameters"]
    ax.plot(best[0], best[1], "r*", ms=16, label=f"best run (J = {meta['best']['objective']:.4g})")
    opt = meta["surrogate"]["predicted_optimum"]
    ax.plot(opt[0], opt[1], "mx", ms=12, mew=3, label="surrogate optimum")
    ax.set_xlabel(p0)
    ax.set_ylabel(p1)
    ax.set_title("objective surface (GP mean) and runs")
    ax.legend(loc="best", fontsize=8)
    # Stress-strain curves.
    best_i = int(meta["best"]["run"].split("_")[1])
    for i in range(len(x)):
        h = os.path.join(d, "runs", f"run_{i:03d}", "history.csv")
        if not os.path.exists(h) or not np.isfinite(j[i]):
            continue
        c = read_csv(h)
        kw = dict(color="red", lw=2, zorder=3, label=f"best run {i}") if i == best_i else dict(color="0.7", lw=0.8)
        bx.plot(100 * num(c["strain"]), num(c["top_stress_Pa"]) / 1e6, **kw)
    tf = meta["target"]["stress_strain_csv"]
    if tf and os.path.exists(tf):
        t = read_csv(tf)
        col = "stress_Pa" if "stress_Pa" in t else "top_stress_Pa"
        bx.plot(100 * num(t["strain"]), num(t[col]) / 1e6, "k--", lw=1.5, label="target")
    if meta["target"]["yield_stress_Pa"] > 0:
        bx.axhline(meta["target"]["yield_stress_Pa"] / 1e6, color="b", ls=":", label="target yield")
    bx.set_xlabel("axial strain, %")
    bx.set_ylabel("top platen stress, MPa")
    bx.set_title("stress-strain: target and runs")
    bx.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    out = os.path.join(d, "objective_surface.png")
    fig.savefig(out + ".tmp.png", dpi=110)
    os.replace(out + ".tmp.png", out)


if __name__ == "__main__":
    main(sys.argv[1])

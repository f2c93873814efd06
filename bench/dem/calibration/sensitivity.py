#!/usr/bin/python3
"""How sharply do sigma_t0 and lambda show in the small cell's response?
(bench/dem/RESULTS.md, "Calibration"). Usage: sensitivity.py TOMOGRAIN OUT

1. Perturbations around sigma_t0 = 12 MPa, lambda = 1.25 (strength seed 1),
   the cell (small_cell.toml) run to 12 % strain: curve misfit
   RMS(d sigma) / RMS(sigma) against the centre run, up to 4/5/6/8/12 % strain.
2. lambda 0.9 / 1.25 / 1.6 at sigma_t0 = 12 MPa with strength seeds 1-4, to
   8 %: mean top stress over 1-8 % strain, grains and bonds broken at 8 %.
Two runs at a time, one thread each; runs already in OUT are reused.
"""
import csv
import os
import subprocess
import sys

import numpy as np

TG, OUT = os.path.abspath(sys.argv[1]), sys.argv[2]
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
BASE = open(os.path.join(HERE, "small_cell.toml")).read().replace('"../../../tests', f'"{ROOT}/tests')
ENV = dict(os.environ, OMP_NUM_THREADS="1", TOMOGRAIN_QUIET="1")


def run_all(cases):
    """cases: {name: extra config text}; runs the missing ones, two at a time."""
    todo = []
    for name, extra in cases.items():
        d = os.path.join(OUT, name)
        if os.path.exists(os.path.join(d, "history.csv")):
            continue
        with open(d + ".toml", "w") as f:
            f.write(extra)
        todo.append(["nice", "-n", "10", TG, "dem", "oedometer", d + ".toml", "-o", d])
    running = []
    while todo or running:
        while todo and len(running) < 2:
            running.append(subprocess.Popen(todo.pop(0), env=ENV, stdout=subprocess.DEVNULL))
        running.pop(0).wait()


def history(name):
    r = list(csv.DictReader(open(os.path.join(OUT, name, "history.csv"))))
    return {k: np.array([float(x[k]) for x in r]) for k in ("strain", "top_stress_Pa", "grains_broken", "bonds_broken")}


def main():
    os.makedirs(OUT, exist_ok=True)
    b12 = BASE.replace("target_strain = 0.08", "target_strain = 0.12")
    pert = {"centre": (12e6, 1.25), "s-5": (11.4e6, 1.25), "s+5": (12.6e6, 1.25), "s-2.5": (11.7e6, 1.25),
            "l-5": (12e6, 1.1875), "l+5": (12e6, 1.3125), "l-2.4": (12e6, 1.22)}
    run_all({f"p_{k}": b12 + f"sigma_t0_Pa = {s}\nbond_radius_multiplier = {l}\n" for k, (s, l) in pert.items()})
    t = history("p_centre")
    print("perturbation: curve misfit against the centre run up to 4 / 5 / 6 / 8 / 12 % strain")
    for k, (s, l) in pert.items():
        if k == "centre":
            continue
        h = history(f"p_{k}")
        m = []
        for emax in (0.04, 0.05, 0.06, 0.08, 0.12):
            sel = (t["strain"] > 0.005) & (t["strain"] <= emax)
            d = np.interp(t["strain"][sel], h["strain"], h["top_stress_Pa"]) - t["top_stress_Pa"][sel]
            m.append(np.sqrt(np.mean(d ** 2)) / np.sqrt(np.mean(t["top_stress_Pa"][sel] ** 2)))
        print(f"  sigma_t0 {s / 1e6:.2f} MPa, lambda {l:.4f}: " + " / ".join(f"{x:.3f}" for x in m))
    lams, seeds = (0.9, 1.25, 1.6), (1, 2, 3, 4)
    run_all({f"e_l{l}_s{k}": BASE + f"sigma_t0_Pa = 12e6\nbond_radius_multiplier = {l}\nseed = {k}\n"
             for l in lams for k in seeds})
    g = np.linspace(0.01, 0.08, 71)
    print("lambda x strength seed, sigma_t0 12 MPa, to 8 %:")
    for l in lams:
        hs = [history(f"e_l{l}_s{k}") for k in seeds]
        m = [np.interp(g, h["strain"], h["top_stress_Pa"]).mean() / 1e6 for h in hs]
        gb = [h["grains_broken"][-1] for h in hs]
        bb = [h["bonds_broken"][-1] for h in hs]
        print(f"  lambda {l}: mean stress 1-8 % {np.mean(m):.3f} MPa (seeds {' '.join(f'{x:.3f}' for x in m)}), "
              f"grains broken {np.mean(gb):.1f} +- {np.std(gb, ddof=1):.1f}, bonds {np.mean(bb):.0f} +- {np.std(bb, ddof=1):.0f}")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""How long do new fragments hold together, and are they born loaded? (issue 21, frag21)

Usage: fragment_birth.py RUNDIR [RUNDIR ...]

Needs a run made with `breakage.log_bond_breaks = true` (RUNDIR/bond_breaks.csv)
and the birth columns of splits.csv (mother_overlap_ratio, fragment_overlap_ratio,
fragment_contacts, fragment_force_N). Prints, per run:
  * bonds broken by stress by age (steps since their fragment's split, and µs),
    as counts and as the share of all fragment bonds made (80 per split);
  * per generation of the mother: the mother's largest overlap / R at the check,
    the largest overlap / r of her 34 new spheres as placed, the share of splits
    whose new spheres are born touching a neighbour, and the largest Hertz
    force at birth against the tensile capacity sigma_c * A of the fragment's
    weakest bond (ring B - ring A, R_bar = lambda (rA + rB)/2 of the template);
  * for splits alone in their check (their bonds are told apart by birth step):
    the share of their 80 bonds broken within 100 steps, for splits born with
    a Hertz force above / below that capacity, and born untouched.
Rules stated, not tuned: medians and 10/90 % quantiles; `age` = steps the bond
was updated (bond_breaks.csv).
"""
import csv
import math
import os
import statistics
import sys
import tomllib

RA, RB = 0.263301141, 0.160975  # template radii / mother radius (dem/breakage/README.md)


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def q(v, p):
    v = sorted(v)
    return v[min(len(v) - 1, int(p * len(v)))] if v else float("nan")


def config(run):
    cfg = tomllib.load(open(os.path.join(run, "config.toml"), "rb"))
    b = cfg.get("breakage", {})
    return b.get("bond_radius_multiplier", 1.25), b.get("bond_normal_strength_Pa", 3.3e6), b.get("bond_radius_rule", "mean")


def main():
    for run in sys.argv[1:]:
        lam, sigma_c, rule = config(run)
        splits = rows(os.path.join(run, "splits.csv"))
        breaks = rows(os.path.join(run, "bond_breaks.csv"))
        hist = rows(os.path.join(run, "history.csv"))
        dt_end = float(hist[-1]["time_step_s"])
        made = 80 * len(splits)
        print(f"## {run}\n\n{len(splits)} splits ({made} fragment bonds made), {len(breaks)} bonds broken by stress "
              f"({100 * len(breaks) / max(1, made):.1f} %); lambda {lam} ({rule}), sigma_c {sigma_c / 1e6:.2f} MPa; dt at end {dt_end:.2g} s\n")
        ages = [int(float(r["age_steps"])) for r in breaks if int(float(r["age_steps"])) >= 0]
        ages_us = [1e6 * float(r["age_s"]) for r in breaks if int(float(r["age_steps"])) >= 0]
        edges = [1, 10, 100, 1000, 10000, 100000, 10 ** 9]
        print("| age (steps since the split) | bonds broken | share of broken | share of bonds made | cumulative share of made |")
        print("|---|---|---|---|---|")
        lo, cum = 0, 0
        for hi in edges:
            n = sum(1 for a in ages if lo < a <= hi)
            cum += n
            lab = f"{lo + 1}-{hi}" if hi < 10 ** 9 else f"> {lo}"
            print(f"| {lab} | {n} | {100 * n / max(1, len(ages)):.1f} % | {100 * n / max(1, made):.1f} % | {100 * cum / max(1, made):.1f} % |")
            lo = hi
        print(f"\nage: median {q(ages, 0.5)} steps = {q(ages_us, 0.5):.2f} us; 10 % {q(ages, 0.1)} steps "
              f"({q(ages_us, 0.1):.2f} us); 90 % {q(ages, 0.9)} steps ({q(ages_us, 0.9):.1f} us); "
              f"tensile {100 * sum(int(float(r['tensile'])) for r in breaks) / max(1, len(breaks)):.0f} %")
        by_gen = {}
        for r in breaks:
            by_gen.setdefault(int(float(r["generation"])), []).append(int(float(r["age_steps"])))
        print("by generation of the bond's spheres: " + "; ".join(
            f"gen {g}: {len(v)} broken, median age {q(v, 0.5)} steps, {100 * sum(1 for a in v if a <= 100) / len(v):.0f} % within 100"
            for g, v in sorted(by_gen.items())))
        print("\n| mother generation | splits | mother overlap / R, median (10-90 %) | new spheres' largest overlap / r as placed | "
              "born touching | Hertz force at birth, median (90 %) N | capacity sigma_c A of the weakest bond, median N | force > capacity |")
        print("|---|---|---|---|---|---|---|---|")
        cap = {}
        for g in sorted({int(float(s["generation"])) for s in splits}):
            ss = [s for s in splits if int(float(s["generation"])) == g]
            mo = [float(s["mother_overlap_ratio"]) for s in ss]
            fo = [float(s["fragment_overlap_ratio"]) for s in ss]
            ff = [float(s["fragment_force_N"]) for s in ss]
            caps = []
            for s in ss:
                R = 0.5 * float(s["diameter_m"])
                rbar = lam * (min(RA, RB) * R if rule == "min" else 0.5 * (RA + RB) * R)
                c = sigma_c * math.pi * rbar * rbar
                caps.append(c)
                cap[id(s)] = c
            touch = sum(1 for s in ss if int(float(s["fragment_contacts"])) > 0)
            over = sum(1 for f, c in zip(ff, caps) if f > c)
            print(f"| {g} | {len(ss)} | {q(mo, .5):.3f} ({q(mo, .1):.3f}-{q(mo, .9):.3f}) | {q(fo, .5):.3f} ({q(fo, .1):.3f}-{q(fo, .9):.3f}) "
                  f"| {100 * touch / len(ss):.0f} % | {q(ff, .5):.2f} ({q(ff, .9):.2f}) | {q(caps, .5):.2f} | {100 * over / len(ss):.0f} % |")
        # Splits alone in their check: their bonds are the ones born at that step.
        count = {}
        for s in splits:
            count[int(float(s["step"]))] = count.get(int(float(s["step"])), 0) + 1
        early = {}
        for r in breaks:
            if int(float(r["age_steps"])) >= 0 and int(float(r["age_steps"])) <= 100:
                early[int(float(r["born_step"]))] = early.get(int(float(r["born_step"])), 0) + 1
        groups = {"born with F > capacity": [], "born touching, F <= capacity": [], "born untouched": []}
        for s in splits:
            st = int(float(s["step"]))
            if count[st] != 1:
                continue
            share = early.get(st, 0) / 80
            f = float(s["fragment_force_N"])
            key = ("born untouched" if int(float(s["fragment_contacts"])) == 0 else
                   "born with F > capacity" if f > cap[id(s)] else "born touching, F <= capacity")
            groups[key].append(share)
        print("\nsplits alone in their check, share of their 80 bonds broken within 100 steps: " + "; ".join(
            f"{k}: {len(v)} splits, mean {100 * statistics.mean(v):.0f} %" if v else f"{k}: none" for k, v in groups.items()))
        print()


if __name__ == "__main__":
    main()

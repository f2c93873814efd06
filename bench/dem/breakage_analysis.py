#!/usr/bin/env python3
"""Closing figures of a breakage oedometer run (issue 7), each beside the study's.

Usage: breakage_analysis.py RUNDIR [N_GRAINS]

Reads RUNDIR/history.csv, RUNDIR/splits.csv and RUNDIR/run.json (written by
`tomograin dem oedometer`). Rules (stated, not tuned):
  * yield stress: `tomograin dem yield RUNDIR/history.csv` (dem/yield_stress.hpp, the rule
    of the report and of `dem calibrate`): strain against log10(stress) above 0.1 MPa,
    two least-squares lines split where they leave the least residual (the second at
    least 1.5 times as steep: a knee), crossing at the yield. The binary is $TOMOGRAIN, else build/release/apps/tomograin of this checkout.
  * "at 4 MPa": the first history row with sigma_top >= 4 MPa.
  * breakage vs height: generation-0 splits (grains broken), binned by the
    grain centre's height at the split divided by the platen height then
    (z / h(t), h(t) = H0 - v t), 5 equal bins from the bottom platen.
"""
import csv
import json
import math
import os
import subprocess
import sys


def read_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]} if rows else {}


def yield_stress_mpa(run):
    """The yield of a run in MPa (nan: none), by the product's one rule."""
    here = os.path.dirname(os.path.abspath(__file__))
    exe = os.environ.get("TOMOGRAIN", os.path.join(here, "..", "..", "build", "release", "apps", "tomograin"))
    out = subprocess.run([exe, "dem", "yield", os.path.join(run, "history.csv")], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{exe} dem yield {run}/history.csv: {out.stderr.strip()}")
    return float(out.stdout.split()[1])


def main():
    run = sys.argv[1]
    h = read_csv(f"{run}/history.csv")
    info = json.load(open(f"{run}/run.json"))
    n0 = int(sys.argv[2]) if len(sys.argv) > 2 else int(info["spheres"])
    h0 = info["initial_height_m"]
    sig = h["top_stress_Pa"]
    sy = yield_stress_mpa(run) * 1e6

    def at(cond):
        for i in range(len(sig)):
            if cond(i):
                return i
        return None

    i_y = at(lambda i: sig[i] >= sy)
    i_4 = at(lambda i: sig[i] >= 4e6)
    last = len(sig) - 1

    def row(i):
        if i is None:
            return "not reached"
        return (f"strain {100*h['strain'][i]:.2f} %, sigma {sig[i]/1e6:.2f} MPa: grains broken {int(h['grains_broken'][i])}, "
                f"bonds broken {int(h['bonds_broken'][i])} (+{int(h['bonds_dropped'][i])} dropped with split elements), "
                f"spheres {int(h['spheres'][i])}, fines removed {int(h['fines_removed'][i])}")

    print(f"run {run}: {n0} grains, H0 {1e3*h0:.3f} mm, initial porosity {100*info['initial_porosity']:.2f} %")
    print(f"yield stress (bilinear strain-log sigma, tomograin dem yield): {sy/1e6:.2f} MPa   [study ~2 MPa]")
    print(f"at yield: {row(i_y)}   [study: 20 grains / 300 bonds]")
    print(f"at 4 MPa: {row(i_4)}   [study: 280 grains / 10 000 bonds]")
    print(f"at end:   {row(last)}")
    print(f"intact grains broken at the end: {100*h['grains_broken'][last]/n0:.1f} %   [study 35 %]")
    print(f"final: spheres {int(h['spheres'][last])}, particles {int(h['particles'][last])}, "
          f"volume lost {1e9*h['volume_lost_m3'][last]:.3f} mm3 (fines {1e9*h['fines_volume_m3'][last]:.4f}), "
          f"added mass fraction {h['added_mass_fraction'][last]:.2e}, dt {h['time_step_s'][last]:.3g} s, "
          f"max KE {max(h['kinetic_energy_J']):.3g} J")
    # Quasi-static check: kinetic energy against the work done by the platen so far.
    area = math.pi * info.get("cylinder_radius_m", 7.5e-3) ** 2
    work, ratio = 0.0, 0.0
    for i in range(1, len(sig)):
        work += 0.5 * (sig[i] + sig[i - 1]) * area * (h["platen_z_m"][i - 1] - h["platen_z_m"][i])
        if sig[i] > 0.1e6:
            ratio = max(ratio, h["kinetic_energy_J"][i] / work)
    print(f"platen work {work:.3g} J; max kinetic energy / work so far (sigma > 0.1 MPa) {ratio:.2e}")
    try:
        sp = read_csv(f"{run}/splits.csv")
    except (FileNotFoundError, StopIteration):
        sp = {}
    if sp:
        v = 0.1
        bins = [0] * 5
        for g, z, t in zip(sp["generation"], sp["z_m"], sp["time_s"]):
            if g != 0:
                continue
            rel = z / (h0 - v * t)
            bins[min(4, max(0, int(rel * 5)))] += 1
        print("grains broken by height (z/h, bottom -> top): " +
              ", ".join(f"{k/5:.1f}-{(k+1)/5:.1f}: {c}" for k, c in enumerate(bins)) +
              "   [study: more near the platens]")
        gens = {}
        for g in sp["generation"]:
            gens[int(g)] = gens.get(int(g), 0) + 1
        print("splits by generation: " + ", ".join(f"gen {g}: {c}" for g, c in sorted(gens.items())))


if __name__ == "__main__":
    main()

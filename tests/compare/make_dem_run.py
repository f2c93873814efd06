#!/usr/bin/python3
"""A small stand-in DEM run folder for the report test, made from a synthetic
specimen's stage-0 truth table (tomograin synth): NOT a DEM simulation.

  RUN/snapshots/strain_00.00pct.h5  the grains as spheres, in the DEM snapshot
                                    format (group /spheres, root attribute
                                    "snapshot" = {"strain": ...})
  RUN/snapshots/strain_07.12pct.csv the packing compressed by 7.12 % in z with
                                    every third grain split into two fragments,
                                    each a cluster of two overlapping spheres
                                    (one particle id per fragment), column strain
  RUN/history.csv                   strain, top_stress_Pa, broken_grains
  EXP.csv                           an invented experimental curve (axial_strain,
                                    axial_stress_MPa)
Usage: make_dem_run.py STAGE0_TRUTH.csv RUN EXP.csv
"""
import csv
import json
import os
import sys

import h5py
import numpy as np

truth, run, exp = sys.argv[1:4]
rows = list(csv.DictReader(open(truth)))
c = np.array([[float(r["cx_mm"]), float(r["cy_mm"]), float(r["cz_mm"])] for r in rows]) * 1e-3
rad = np.array([float(r["radius_mm"]) for r in rows]) * 1e-3
os.makedirs(os.path.join(run, "snapshots"), exist_ok=True)

with h5py.File(os.path.join(run, "snapshots", "strain_00.00pct.h5"), "w") as f:
    g = f.create_group("spheres")
    for k, name in enumerate(["x_m", "y_m", "z_m"]):
        g[name] = c[:, k]
    g["r_m"] = rad
    g["particle"] = np.arange(len(rad), dtype=np.float64)
    g.attrs["columns"] = np.bytes_("x_m,y_m,z_m,r_m,particle")  # core/io/hdf5's table convention
    f.attrs["snapshot"] = np.bytes_(json.dumps({"strain": 0.0, "requested_strain": 0.0}))

strain = 0.0712
out = []  # x, y, z, r, particle
pid = 0
broken = 0
for q in range(len(rad)):
    x, y, z = c[q]
    z *= 1 - strain
    r = rad[q]
    if q % 3 == 1:
        broken += 1
        for side in (-1, 1):
            for dx in (-0.25 * r, 0.25 * r):
                out.append((x + dx, y, z + side * 0.5 * r, 0.45 * r, pid))
            pid += 1
    else:
        out.append((x, y, z, r, pid))
        pid += 1
with open(os.path.join(run, "snapshots", "strain_07.12pct.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["x_m", "y_m", "z_m", "r_m", "particle", "strain"])
    for row in out:
        w.writerow([repr(float(v)) for v in row[:4]] + [row[4], strain])

e = np.linspace(0, 0.08, 41)
with open(os.path.join(run, "history.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["step", "strain", "top_stress_Pa", "broken_grains"])
    for k, ek in enumerate(e):
        w.writerow([k * 1000, ek, 2e6 * (1 - np.exp(-ek / 0.02)) + 1e7 * ek, round(broken * min(1, ek / strain))])
with open(exp, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["axial_strain", "axial_stress_MPa"])
    for ek in e:
        w.writerow([ek, 1.8 * (1 - np.exp(-ek / 0.025)) + 9 * ek])

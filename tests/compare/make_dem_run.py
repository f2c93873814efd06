#!/usr/bin/python3
"""A stand-in DEM run folder made from a synthetic specimen's stage-0 truth
table (tomograin synth): NOT a DEM simulation; a fixture for the report test
and for measuring the segmentation bias on fragment clusters.

  RUN/snapshots/strain_00.00pct.h5  the grains as spheres, in the DEM snapshot
                                    format (group /spheres with a "columns"
                                    attribute, root attribute "snapshot" =
                                    {"strain": ...}), as dem/snapshot.cpp writes
  RUN/snapshots/strain_XX.XXpct.csv one per later strain: the packing compressed
                                    in z by the strain, a fraction of the grains
                                    replaced by two 17-sphere fragments each (the
                                    DEM template of dem/breakage/fragment_template.hpp:
                                    ring A of 8 spheres ra = 0.26330 on the plane,
                                    a central sphere rc = 0.44948, ring B of 8
                                    spheres rb = 0.16097 at 45 degrees), splitting
                                    plane normal drawn at random; column strain;
                                    column previous_particle (dem/particles.hpp): a
                                    grain's particle, or the same-side fragment of a
                                    grain already split, at the previous snapshot
  RUN/snapshots.csv                 the snapshot index (dem/run_folder.hpp: file, step,
                                    time_s, axial_strain, requested_strain, bonds)
  RUN/history.csv                   strain, top_stress_Pa, grains_broken (invented curve; DEM column names)
  EXP.csv                           an invented experimental curve (axial_strain,
                                    axial_stress_MPa)
Usage: make_dem_run.py STAGE0_TRUTH.csv RUN EXP.csv [STRAINS BROKEN]
       STRAINS, BROKEN: comma lists, e.g. 0,0.0712 and 0,0.3 (the default).
"""
import csv
import json
import math
import os
import sys

import h5py
import numpy as np

truth, run, exp = sys.argv[1:4]
strains = [float(v) for v in (sys.argv[4] if len(sys.argv) > 4 else "0,0.0712").split(",")]
broken = [float(v) for v in (sys.argv[5] if len(sys.argv) > 5 else "0,0.3").split(",")]
rows = list(csv.DictReader(open(truth)))
c = np.array([[float(r["cx_mm"]), float(r["cy_mm"]), float(r["cz_mm"])] for r in rows]) * 1e-3
rad = np.array([float(r["radius_mm"]) for r in rows]) * 1e-3
os.makedirs(os.path.join(run, "snapshots"), exist_ok=True)

# Fragment template in mother radii, fragment on the z > 0 side.
RA, RC, RB = 0.26330, 0.44948, 0.16097
TEMPLATE = [((0.0, 0.0, RC), RC)]
rho_a = math.sqrt((1 - RA) ** 2 - RA ** 2)
for k in range(8):
    a = k * math.pi / 4
    TEMPLATE.append(((rho_a * math.cos(a), rho_a * math.sin(a), RA), RA))
for k in range(8):
    a = math.pi / 8 + k * math.pi / 4
    d = (1 - RB) / math.sqrt(2)
    TEMPLATE.append(((d * math.cos(a), d * math.sin(a), d), RB))


def frame(n):
    n = n / np.linalg.norm(n)
    t = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(n, t)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1), n


def write_h5(path, strain):
    with h5py.File(path, "w") as f:
        g = f.create_group("spheres")
        for k, name in enumerate(["x_m", "y_m", "z_m"]):
            g[name] = c[:, k]
        g["r_m"] = rad
        g["particle"] = np.arange(len(rad), dtype=np.float64)
        g["previous_particle"] = np.arange(len(rad), dtype=np.float64)  # the run's start: the same grains
        g.attrs["columns"] = np.bytes_("x_m,y_m,z_m,r_m,particle,previous_particle")  # core/io/hdf5's table convention
        f.attrs["snapshot"] = np.bytes_(json.dumps({"strain": strain, "requested_strain": strain}))


index = []  # rows of RUN/snapshots.csv
rng = np.random.default_rng(11)
order = rng.permutation(len(rad))  # grains break in this order as the strain grows
n_broken = []
prev_ids = {q: [q] for q in range(len(rad))}  # grain -> its particle ids (one, or one per fragment side) at the last snapshot
for s, (strain, frac) in enumerate(zip(strains, broken)):
    nb = int(round(frac * len(rad)))
    n_broken.append(nb)
    if s == 0 and nb == 0:
        write_h5(os.path.join(run, "snapshots", "strain_00.00pct.h5"), strain)
        index.append(("snapshots/strain_00.00pct.h5", strain))
        continue
    split = set(order[:nb].tolist())
    out, pid, ids = [], 0, {}
    for q in range(len(rad)):
        x, y, z = c[q]
        centre = np.array([x, y, z * (1 - strain)])
        r = rad[q]
        if q in split:
            e1, e2, n = frame(rng.normal(size=3))
            for k, side in enumerate((1.0, -1.0)):  # two mirrored fragments
                prev = prev_ids[q][k if len(prev_ids[q]) == 2 else 0]
                for (tx, ty, tz), tr in TEMPLATE:
                    p = centre + r * (tx * e1 + ty * e2 + side * tz * n)
                    out.append((p[0], p[1], p[2], r * tr, pid, prev))
                ids.setdefault(q, []).append(pid)
                pid += 1
        else:
            out.append((centre[0], centre[1], centre[2], r, pid, prev_ids[q][0]))
            ids[q] = [pid]
            pid += 1
    prev_ids = ids
    name = "strain_%05.2fpct.csv" % (100 * strain)
    with open(os.path.join(run, "snapshots", name), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x_m", "y_m", "z_m", "r_m", "particle", "previous_particle", "strain"])
        for row in out:
            w.writerow([repr(float(v)) for v in row[:4]] + [row[4], row[5], strain])
    index.append(("snapshots/" + name, strain))

with open(os.path.join(run, "snapshots.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["file", "step", "time_s", "axial_strain", "requested_strain", "bonds"])
    for k, (name, strain) in enumerate(index):
        w.writerow([name, k * 1000, k * 1e-4, strain, strain, ""])

e = np.linspace(0, max(strains) * 1.05, 41)
with open(os.path.join(run, "history.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["step", "strain", "top_stress_Pa", "grains_broken"])
    for k, ek in enumerate(e):
        w.writerow([k * 1000, ek, 2e6 * (1 - np.exp(-ek / 0.02)) + 1e7 * ek, np.interp(ek, strains, n_broken)])
with open(exp, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["axial_strain", "axial_stress_MPa"])
    for ek in e:
        w.writerow([ek, 1.8 * (1 - np.exp(-ek / 0.025)) + 9 * ek])

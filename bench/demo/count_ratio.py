#!/usr/bin/python3
"""Particles above the detection limit (below_limit = 0, d_eq >= 0.2 mm) in
the ideal and imaged DEM paths of a compare report, per stage, from
REPORT/particles/stageN_dem_{ideal,imaged}.csv.
Usage: count_ratio.py REPORT_DIR"""
import csv
import glob
import os
import sys

rep = sys.argv[1]


def counts(path):
    rows = list(csv.DictReader(open(path)))
    return len(rows), sum(1 for r in rows if r["below_limit"] in ("0", "false"))


for ideal in sorted(glob.glob(os.path.join(rep, "particles", "stage*_dem_ideal.csv"))):
    stage = os.path.basename(ideal).split("_")[0]
    n_id, a_id = counts(ideal)
    n_im, a_im = counts(ideal.replace("_dem_ideal", "_dem_imaged"))
    print(f"{stage}: ideal {n_id} particles ({a_id} above the limit), imaged {n_im} ({a_im} above), "
          f"imaged/ideal above the limit {a_im / max(a_id, 1):.3f}")

#!/usr/bin/env python3
"""Convert a tomograin packing CSV (x_m,y_m,z_m,r_m) into a LIGGGHTS data
file (atom_style granular: id type diameter density x y z), so both engines
start from the same spheres.
Usage: csv_to_liggghts.py packing.csv out.data [density [half_width_m]]
The box is [-w, w]^2 in x, y with w = half_width_m, default the larger of
9 mm (the study's Ø15 mm cell and its 8.5 mm platen mesh) and the spheres'
extent + 1.5 mm; z from -0.5 mm to 2 mm above the highest sphere."""
import csv
import math
import sys

src, dst = sys.argv[1], sys.argv[2]
rho = float(sys.argv[3]) if len(sys.argv) > 3 else 2180.0
rows = list(csv.DictReader(open(src)))
zmax = max(float(r["z_m"]) + float(r["r_m"]) for r in rows)
extent = max(math.hypot(float(r["x_m"]), float(r["y_m"])) + float(r["r_m"]) for r in rows)
w = float(sys.argv[4]) if len(sys.argv) > 4 else max(0.009, extent + 0.0015)
with open(dst, "w") as f:
    f.write("tomograin packing %s\n\n%d atoms\n1 atom types\n\n" % (src, len(rows)))
    f.write("%.6f %.6f xlo xhi\n%.6f %.6f ylo yhi\n-0.0005 %.6f zlo zhi\n\nAtoms\n\n" % (-w, w, -w, w, zmax + 0.002))
    for i, r in enumerate(rows, 1):
        f.write("%d 1 %.17g %.17g %.17g %.17g %.17g\n" % (i, 2 * float(r["r_m"]), rho, float(r["x_m"]), float(r["y_m"]), float(r["z_m"])))

#!/usr/bin/python3
"""scikit-image regionprops on the label volumes of measure_feret_bench, for
the side-by-side table in bench/measure/RESULTS.md.

    TG_DUMP=/tmp/small.raw build/release/bench/measure/measure_feret_bench small 256 24000
    /usr/bin/python3 bench/measure/skimage_regionprops.py /tmp/small.raw 256 256 256 [--feret]

Times skimage.measure.regionprops_table (one thread: skimage does not
parallelise it) with the properties closest to tomograin's particle table:
label, area (voxels), centroid, bbox, inertia_tensor_eigvals (principal
moments), axis_major_length / axis_minor_length (equivalent ellipsoid);
--feret adds feret_diameter_max (3-D: marching cubes, then the largest
pairwise distance of the mesh's hull vertices), on the first 2000 labels only
and reported per particle, since it is slow. Wall and CPU time
(time.process_time) are printed.
"""
import sys
import time

import numpy as np
from skimage import measure


def main():
    path, nz, ny, nx = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    labels = np.fromfile(path, dtype=np.uint32).reshape(nz, ny, nx)
    props = ["label", "area", "centroid", "bbox", "inertia_tensor_eigvals", "axis_major_length", "axis_minor_length"]
    t0, c0 = time.perf_counter(), time.process_time()
    table = measure.regionprops_table(labels, properties=props)
    t, c = time.perf_counter() - t0, time.process_time() - c0
    n = len(table["label"])
    print(f"skimage {__import__('skimage').__version__} regionprops_table {props}: {n} particles in "
          f"{t:.2f} s wall, {c:.2f} s CPU = {n / t:.0f} particles/s")
    if "--feret" in sys.argv:
        rp = measure.regionprops(labels)[:2000]
        t0 = time.perf_counter()
        d = [r.feret_diameter_max for r in rp]
        t = time.perf_counter() - t0
        print(f"skimage feret_diameter_max on {len(rp)} particles: {t:.2f} s = {len(rp) / t:.0f} particles/s "
              f"(median {np.median(d):.2f} voxels)")


if __name__ == "__main__":
    main()

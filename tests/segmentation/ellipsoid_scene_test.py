#!/usr/bin/python3
"""Checks of bench/segmentation/ellipsoid_scene.py, the second blind
generator (issue 19), against analytic answers:

  * a grain clear of the faces and of the others holds 4/3 pi r^3 voxels
    (r its equivalent radius: the axes are scaled so that abc = r^3) within
    3 %; two halves hold the ball less the gap's slab through its centre,
    pi r^2 gap for a ball (an ellipsoid's central section is at least
    pi c^2 and at most pi a^2: the pair lies between those bounds)
  * the truth table lists exactly the labels in the volume, with their
    voxel counts; a parent has at most two halves
  * the noise: the standard deviation of the grey far inside the void is
    20000 / CNR within 3 %; the voxel size carries --z-scale
  * --grain-contrast LO,HI: deep inside each grain the grey is 10000 +
    20000 c (noise off) with c in [LO, HI], one c per grain (its halves
    alike), the c spread over the range; the truth and the void are the
    default scene's

usage: ellipsoid_scene_test.py [WORKDIR]     (~5 s)
"""
import csv
import math
import os
import subprocess
import sys
import tempfile
from collections import Counter

import h5py
import numpy as np
from scipy import ndimage

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GEN = os.path.join(ROOT, "bench", "segmentation", "ellipsoid_scene.py")
FAILS = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILS.append(what)


def scene(work, name, *args):
    pre = os.path.join(work, name)
    subprocess.run([sys.executable, GEN, "-o", pre, *args], check=True, stdout=subprocess.DEVNULL)
    with h5py.File(pre + ".h5", "r") as f:
        scan, truth, vs = f["scan"][...], f["labels"][...], f.attrs["voxel_size_m"]
    with open(pre + "_truth.csv") as f:
        table = list(csv.DictReader(f))
    return scan, truth, np.asarray(vs), table


def main():
    if len(sys.argv) < 2:
        with tempfile.TemporaryDirectory(prefix="ellipsoid_scene_test_") as work:
            return run(work)
    os.makedirs(sys.argv[1], exist_ok=True)
    return run(sys.argv[1])


def run(work):
    # Sparse grains (fill 0.12), half of them cut with a 1.5-voxel gap.
    scan, truth, vs, table = scene(work, "sparse", "--size", "64,72,80", "--radius", "8", "--fill", "0.12",
                                   "--min-distance", "1.3", "--split-frac", "0.5", "--gap", "1.5",
                                   "--cnr", "10", "--z-scale", "1.5", "--seed", "3")
    counts = np.bincount(truth.ravel())
    labels = [int(r["label"]) for r in table]
    present = set(np.flatnonzero(counts).tolist()) - {0}
    check(present == set(labels), f"the table lists exactly the labels in the volume ({len(labels)} particles)")
    check(all(int(r["volume_vox"]) == counts[int(r["label"])] for r in table), "table volumes equal label counts")
    by_parent = Counter(r["parent"] for r in table if r["kind"] == "half")
    check(max(by_parent.values(), default=0) <= 2, "a parent has at most two halves")
    check(abs(vs[0] / vs[2] - 1.5) < 1e-9 and abs(vs[2] - 12.3e-6) < 1e-12, f"voxel size carries the z scale: {vs}")
    inner = [r for r in table if r["touches_border"] == "0"]
    whole = [r for r in inner if r["kind"] == "intact"]
    errs = [int(r["volume_vox"]) / (4 / 3 * math.pi * float(r["radius_vox"]) ** 3 / 1.5) - 1 for r in whole]
    check(len(whole) >= 3 and max(abs(e) for e in errs) < 0.03,
          f"whole grains hold 4/3 pi r^3 (z voxels 1.5 long): {len(whole)} grains, errors "
          f"{min(errs):+.4f} .. {max(errs):+.4f}")
    groups = {}
    for r in inner:
        if r["kind"] == "half":
            groups.setdefault(r["parent"], []).append(r)
    pairs = [g for g in groups.values() if len(g) == 2]
    ok = len(pairs) >= 3
    for g in pairs:
        rr = float(g[0]["radius_vox"])
        ball = 4 / 3 * math.pi * rr ** 3
        v = sum(int(h["volume_vox"]) for h in g) * 1.5  # in x-voxel units
        # a, c of the 1 : 0.8 : 0.65 default aspect, scaled to abc = r^3
        a = rr / (0.8 * 0.65) ** (1 / 3)
        lo, hi = ball - math.pi * a * a * 1.5, ball - math.pi * (0.65 * a) ** 2 * 1.5
        ok &= 0.97 * lo <= v <= 1.03 * hi
    check(ok, f"two halves hold the grain less a 1.5-voxel slab through it ({len(pairs)} pairs)")
    far = ndimage.distance_transform_edt(truth == 0, sampling=(1.5, 1, 1)) > 4
    sd = float(scan[far].std())
    check(abs(sd / 2000 - 1) < 0.03, f"void noise sigma {sd:.0f} against 20000 / 10 = 2000")
    # Grains of their own brightness: noiseless, no blur, so a voxel deep in
    # a grain reads its contrast exactly.
    common = ["--size", "48,48,48", "--radius", "7", "--split-frac", "0.3", "--psf", "0.01", "--cnr", "1e9",
              "--seed", "5"]
    plain, t_plain, _, _ = scene(work, "plain", *common)
    dim, t_dim, _, tab = scene(work, "dim", *common, "--grain-contrast", "0.4,0.9")
    check(np.array_equal(t_plain, t_dim), "the contrast leaves the truth as it was")
    boxes = ndimage.find_objects(t_dim)
    share = {}
    ok = True
    for r in tab:
        lab = int(r["label"])
        box = tuple(slice(max(0, b.start - 3), b.stop + 3) for b in boxes[lab - 1])
        mine = t_dim[box] == lab
        v = dim[box][ndimage.distance_transform_edt(mine) > 2.5]  # clear of the void and of other grains
        if v.size == 0:
            continue
        c = (v.astype(float) - 10000) / 20000
        ok &= float(c.max() - c.min()) < 2e-4 and 0.4 - 1e-4 <= float(c.mean()) <= 0.9 + 1e-4
        share.setdefault(r["parent"], []).append(float(c.mean()))
    alike = all(max(v) - min(v) < 2e-4 for v in share.values())
    means = [v[0] for v in share.values()]
    check(ok and alike and len(means) >= 10 and max(means) - min(means) > 0.3,
          f"--grain-contrast 0.4,0.9: one contrast per grain in range, halves alike ({len(means)} grains, "
          f"{min(means):.3f} .. {max(means):.3f})")
    check(bool(np.all(dim[t_dim == 0] <= plain[t_dim == 0])), "the void is no brighter than the default scene's")
    # --dim-grains: a share of the grains at one level, the rest at the solid's.
    two, t_two, _, tab2 = scene(work, "two", *common, "--dim-grains", "0.3,0.45")
    check(np.array_equal(t_plain, t_two), "--dim-grains leaves the truth as it was (the boxes below are its)")
    levels = []
    for r in tab2:
        lab = int(r["label"])
        box = tuple(slice(max(0, b.start - 3), b.stop + 3) for b in boxes[lab - 1])
        v = two[box][ndimage.distance_transform_edt(t_two[box] == lab) > 2.5]
        if v.size:
            levels.append(float((v.astype(float).mean() - 10000) / 20000))
    dim_n = sum(abs(c - 0.45) < 2e-3 for c in levels)
    bright_n = sum(abs(c - 1.0) < 2e-3 for c in levels)
    check(dim_n + bright_n == len(levels) and 0.15 < dim_n / max(1, len(levels)) < 0.45,
          f"--dim-grains 0.3,0.45: {dim_n} of {len(levels)} particles at 0.45, the rest at 1")
    if FAILS:
        print(f"{len(FAILS)} check(s) failed")
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

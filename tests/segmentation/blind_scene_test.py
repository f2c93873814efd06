#!/usr/bin/python3
"""Checks of bench/segmentation/blind_scene.py, the blind sweep's generator
(issue 19), against analytic answers:

  * partial volume: one bumpy ellipsoidal grain (r0 10 voxels) with three
    pores rendered alone; the sum of its solid fraction equals its volume
    (1/3) integral r(u)^3 dOmega (quadrature over 20 000 Fibonacci
    directions) minus the pores' 4/3 pi r^3, within 0.3 %; the filled cover
    (pores counted as solid) equals the volume within 0.3 %
  * split gaps: the integral of (1 - solid fraction) across each split plane
    of a noiseless, unblurred scene equals the requested gap (1.0 and 2.0
    voxels) within 3 % (median over the split grains)
  * CNR measured from the image (deep solid minus deep void over the void's
    standard deviation) equals the requested 13 within 3 %
  * the packing's solid fraction is that of a sand (0.5-0.62); the truth
    table's volumes equal the label counts; labels are 1..n; a parent has at
    most two halves; halves and chips exist
  * --grain-contrast: a grain's deep voxels read its own contrast, one per
    grain (its fragments alike), within the range asked for
  * --shell-frac: the shells' truth is a wall as thick as asked (its deepest
    voxel, by the exact distance map, within half the wall + 1 voxel), open
    (no void enclosed by it alone), and the rest of the scene is the scene
    without the option (same particles but the shells, voxel for voxel)

usage: blind_scene_test.py [WORKDIR]     (~10 s)
"""
import csv
import json
import math
import os
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "bench", "segmentation"))
import blind_scene as bs  # noqa: E402

FAILS = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILS.append(what)


def single_grain():
    rng = np.random.default_rng(5)
    sh = bs.make_shape(rng, 10.0)
    shapes = {k: np.array([sh[k]]) for k in sh}
    g = bs.make_grain(1, np.array([16.3, 15.8, 16.1]), shapes, 0)
    p = bs.Particle(g, "intact", [], np.zeros(3))
    p.pores = [(np.array([3.0, 0, 0]), 2.0), (np.array([-3.0, 1.0, 0]), 1.5), (np.array([0, -4.0, 2.0]), 1.0)]
    solid, truth, _, _ = bs.render([p], (32, 32, 32), 3)
    # volume of the star-shaped body: (1/3) integral of r(u)^3 over the sphere
    n = 20000
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = math.pi * (1 + 5 ** 0.5) * k
    u = np.stack([z, np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi)], 1)
    r = bs.radial(shapes, np.zeros(n, int), u)
    vol = 4 * math.pi / 3 * float(np.mean(r ** 3))
    pores = sum(4 / 3 * math.pi * pr ** 3 for _, pr in p.pores)
    got = float(solid.sum(dtype=np.float64))
    check(abs(got - (vol - pores)) < 0.003 * vol, f"single grain solid {got:.1f} vs analytic {vol - pores:.1f} voxels")
    filled = float((truth > 0).sum())
    check(abs(filled - vol) < 0.01 * vol, f"single grain truth voxels {filled:.0f} vs analytic volume {vol:.1f}")


def scene(work, gap, psf, cnr, seed):
    prefix = os.path.join(work, f"s_g{gap}_p{psf}_c{cnr}")
    bs.main(["-o", prefix, "--size", "96", "--radius", "12", "--gap", str(gap), "--psf", str(psf),
             "--cnr", str(cnr), "--seed", str(seed)])
    return prefix, json.load(open(prefix + ".json"))


def grain_contrast(work):
    """--grain-contrast 0.7,1: noiseless and unblurred, a grain's deep voxels
    (fully solid, two voxels inside its truth) read void + f x contrast, one f
    per grain (its fragments alike) in [0.7, 1]."""
    import h5py
    from scipy import ndimage
    prefix = os.path.join(work, "contrast")
    bs.main(["-o", prefix, "--size", "96", "--radius", "12", "--psf", "0", "--cnr", "0", "--seed", "9",
             "--grain-contrast", "0.7,1.0", "--no-measure"])
    with h5py.File(prefix + ".h5", "r") as f:
        scan = f["scan"][...].astype(np.float64)
        truth = f["labels"][...]
    rows = {int(r["label"]): r for r in csv.DictReader(open(prefix + "_truth.csv"))}
    by_grain = {}
    for lab, r in rows.items():
        deep = ndimage.binary_erosion(truth == lab, iterations=2)
        vals = (scan[deep] - bs.VOID) / (bs.SOLID - bs.VOID)
        vals = vals[vals > 0.5]  # pores are void: out
        if vals.size >= 20:
            by_grain.setdefault(r["parent"], []).append(float(np.median(vals)))
    f = [v for vs in by_grain.values() for v in vs]
    one = all(max(vs) - min(vs) < 1e-3 for vs in by_grain.values())
    check(len(by_grain) >= 20 and min(f) >= 0.7 - 1e-3 and max(f) <= 1.0 + 1e-3 and max(f) - min(f) > 0.2 and one,
          f"grain contrast 0.7-1: {len(by_grain)} grains, f {min(f):.3f}..{max(f):.3f}, one f per grain: {one}")


def shells(work):
    """--shell-frac 0.3 --shell-wall 2,4: walls 2-4 voxels thick, open; the
    other grains as without the option."""
    import h5py
    from scipy import ndimage
    pre, plain = os.path.join(work, "shells"), os.path.join(work, "noshells")
    common = ["--size", "96", "--radius", "14", "--seed", "5", "--psf", "0", "--cnr", "0", "--no-measure"]
    bs.main(["-o", pre, "--shell-frac", "0.3", "--shell-wall", "2,4"] + common)
    bs.main(["-o", plain] + common)
    with h5py.File(pre + ".h5", "r") as f:
        truth = f["labels"][...]
    with h5py.File(plain + ".h5", "r") as f:
        truth0 = f["labels"][...]
    rows = list(csv.DictReader(open(pre + "_truth.csv")))
    kinds = {int(r["label"]): r["kind"] for r in rows}
    shell = [l for l, k in kinds.items() if k == "shell"]
    deep, closed = [], 0
    for l in shell:
        m = truth == l
        if m.sum() < 200:
            continue
        deep.append(float(ndimage.distance_transform_edt(np.pad(m, 1)).max()))
        holes = ndimage.binary_fill_holes(np.pad(m, 1)) & ~np.pad(m, 1)
        closed += int(holes.sum() > 10)
    check(len(deep) >= 5 and max(deep) <= 4 / 2 + 1 and closed == 0,
          f"shells: {len(shell)}, deepest voxel {min(deep):.2f}..{max(deep):.2f} (wall <= 4), closed {closed}")
    # Without the shells the same packing and pores: every non-shell particle's voxels are a particle's
    # there, but where a lens of overlap beside a shell went to the other grain (ownership by cover).
    near = ndimage.binary_dilation(np.isin(truth, shell), iterations=1)
    same = (truth == 0) | np.isin(truth, shell) | (truth0 > 0) | near
    check(same.all() and len(shell) > 0, f"non-shell particles as without the option: {same.mean():.6f}")


def main():
    work = sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="tg_blind_scene_")
    os.makedirs(work, exist_ok=True)
    single_grain()
    prefix, info = scene(work, 1.0, 0.7, 13, 7)
    gap = info["measured_gap_vox"]
    check(gap["n"] >= 5 and abs(gap["median"] - 1.0) < 0.03, f"gap 1.0: measured {gap}")
    cnr = info["measured"]["cnr"]
    check(abs(cnr - 13) < 0.39, f"CNR 13: measured {cnr:.3f}")
    check(0.5 <= info["solid_fraction"] <= 0.62, f"solid fraction {info['solid_fraction']:.3f}")
    import h5py
    with h5py.File(prefix + ".h5", "r") as f:
        truth = f["labels"][...]
        check(f["scan"].dtype == np.uint16 and f["scan"].shape == (96, 96, 96), "scan uint16 96^3")
    rows = list(csv.DictReader(open(prefix + "_truth.csv")))
    counts = np.bincount(truth.ravel())
    check([int(r["label"]) for r in rows] == list(range(1, counts.size)), "labels 1..n, one row each")
    check(all(int(r["volume_vox"]) == counts[int(r["label"])] for r in rows), "truth volumes equal label counts")
    halves = {}
    for r in rows:
        if r["kind"] == "half":
            halves[r["parent"]] = halves.get(r["parent"], 0) + 1
    check(len(halves) >= 5 and max(halves.values()) <= 2, f"{len(halves)} split grains, <= 2 halves each")
    check(any(r["kind"] == "chip" for r in rows), "chips kept as particles")
    _, info2 = scene(work, 2.0, 0.0, 0, 8)
    gap = info2["measured_gap_vox"]
    check(gap["n"] >= 5 and abs(gap["median"] - 2.0) < 0.06, f"gap 2.0: measured {gap}")
    grain_contrast(work)
    shells(work)
    if FAILS:
        sys.exit("FAIL: " + "; ".join(FAILS))
    print("OK")


if __name__ == "__main__":
    main()

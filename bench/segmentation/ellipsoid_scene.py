#!/usr/bin/python3
"""A second, deliberately different generator of blind scans: ellipsoids.

blind_scene.py (this folder) draws near-spherical grains packed by overlap
removal; tomograin's defaults were tuned on data_synth and checked on it.
This one shares no code with either: ellipsoids of random orientation and
aspect (axes a : b : c = 1 : --aspect), radii U(0.8, 1.2) R, placed by
random sequential addition (a candidate overlapping the grains already
placed by more than --overlap of its volume is dropped; --overlap 0.2 with
--min-distance 0.8 gives interpenetrating grains), optionally cut in two
halves through the centre by a plane of random normal with a gap of
--gap voxels (--split-frac of the grains); partial volume by 2^3
supersampling, Gaussian PSF (sigma --psf, the z sigma over --z-scale),
Gaussian noise at contrast-to-noise --cnr on a void/solid grey of
10000/30000; with --grain-contrast LO,HI each grain (its halves alike) has
its own contrast over the void, U(LO, HI) of the solid's (drawn from a
stream of its own: the scene is otherwise the same); --dim-grains FRAC,LEVEL
puts that share of the grains at LEVEL (a second, darker mineral). With --z-scale s the voxels are s times longer along z
(voxel_size_m (s x 12.3, 12.3, 12.3) um).

Truth: the label covering most of a voxel's eight samples, where more than
half of them are solid (half: on every second voxel, so that a grain's truth
volume is its volume). Outputs in blind_scene.py's layout, so that
blind_score.py and sweep.py's scoring read them:
  PREFIX.h5         /scan (uint16), /labels (uint32 truth), voxel_size_m
  PREFIX_truth.csv  label, volume_vox, parent, kind (intact | half),
                    touches_border, pores (0), radius_vox, cz, cy, cx

  ellipsoid_scene.py -o /tmp/e1 --size 96,160,200 --radius 10 --seed 1
"""
import argparse
import csv

import h5py
import numpy as np
from scipy import ndimage


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", required=True, help="output prefix")
    ap.add_argument("--size", default="96,160,200", help="nz,ny,nx voxels (96,160,200)")
    ap.add_argument("--radius", type=float, default=10.0, help="mean equivalent radius R, voxels (10)")
    ap.add_argument("--aspect", default="1,0.8,0.65", help="axes ratio a:b:c (1,0.8,0.65)")
    ap.add_argument("--fill", type=float, default=0.55, help="solid fraction aimed at (0.55)")
    ap.add_argument("--min-distance", type=float, default=0.8,
                    help="centres closer than this x (r1 + r2) are refused at once (0.8)")
    ap.add_argument("--overlap", type=float, default=0.01, help="largest share of a grain inside earlier ones (0.01)")
    ap.add_argument("--split-frac", type=float, default=0.0, help="share of grains cut in halves (0)")
    ap.add_argument("--gap", type=float, default=1.0, help="the halves' gap, voxels (1)")
    ap.add_argument("--psf", type=float, default=0.8, help="Gaussian PSF sigma, voxels (0.8)")
    ap.add_argument("--cnr", type=float, default=10.0, help="contrast over noise sigma (10)")
    ap.add_argument("--z-scale", type=float, default=1.0, help="z voxel edge over the x, y edge (1)")
    ap.add_argument("--grain-contrast", default="1,1",
                    help="LO,HI: each grain's contrast over the void, U(LO, HI) of the solid's (1,1)")
    ap.add_argument("--dim-grains", default="",
                    help="FRAC,LEVEL: that share of the grains at LEVEL of the solid's contrast (another mineral)")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    shape = tuple(int(v) for v in a.size.split(","))
    aspect = np.array([float(v) for v in a.aspect.split(",")])
    ss = 2  # samples per voxel edge
    fine = np.zeros(tuple(n * ss for n in shape), np.uint32)
    zs = a.z_scale
    extent = np.array([shape[0] * zs, shape[1], shape[2]])  # in x-voxel units
    placed, grains = [], []
    volume, tries = 0.0, 0
    while volume < a.fill * extent.prod() and tries < 30000:
        tries += 1
        r = a.radius * rng.uniform(0.8, 1.2)
        axes = r * aspect / np.cbrt(aspect.prod())
        c = rng.uniform(-0.3 * r, extent + 0.3 * r)
        if any(np.linalg.norm(c - c2) < a.min_distance * (r + r2) for c2, r2 in placed):
            continue
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        reach = axes.max() + 1
        lo = [max(0, int((c[d] - reach) / (zs if d == 0 else 1) * ss)) for d in range(3)]
        hi = [min(fine.shape[d], int((c[d] + reach) / (zs if d == 0 else 1) * ss) + 2) for d in range(3)]
        if any(h <= l for l, h in zip(lo, hi)):
            continue
        z, y, x = np.meshgrid(*[(np.arange(lo[d], hi[d]) + 0.5) / ss * (zs if d == 0 else 1) - c[d] for d in range(3)],
                              indexing="ij")
        p = np.stack([z, y, x], -1)
        inside = (((p @ q) / axes) ** 2).sum(-1) <= 1
        sub = fine[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
        if (sub[inside] > 0).sum() > a.overlap * inside.sum():
            continue
        placed.append((c, r))
        gid = len(placed)
        if rng.uniform() < a.split_frac:
            normal = rng.normal(size=3)
            d = p @ (normal / np.linalg.norm(normal))
            for side, keep in ((1, d < -a.gap / 2), (2, d > a.gap / 2)):
                lab = len(grains) + 1
                sub[inside & keep & (sub == 0)] = lab
                grains.append((lab, gid, "half", r, c))
        else:
            lab = len(grains) + 1
            sub[inside & (sub == 0)] = lab
            grains.append((lab, gid, "intact", r, c))
        volume += inside.sum() / ss ** 3 * zs
    # Down to voxels: the solid share, and the label of most samples.
    blocks = fine.reshape(shape[0], ss, shape[1], ss, shape[2], ss).transpose(0, 2, 4, 1, 3, 5).reshape(-1, ss ** 3)
    solid = (blocks > 0).mean(1)
    srt = np.sort(blocks, axis=1)
    best = srt[:, 0].copy()
    best_n = np.zeros(len(srt), np.int32)
    run = np.ones(len(srt), np.int32)
    for k in range(1, ss ** 3):
        run = np.where(srt[:, k] == srt[:, k - 1], run + 1, 1)
        better = (run > best_n) & (srt[:, k] > 0)
        best = np.where(better, srt[:, k], best)
        best_n = np.where(better, run, best_n)
    # Half the samples solid is a tie: solid on every second voxel (by the
    # parity of k + j + i), so that the truth's volume is not biased upward.
    k, j, i = np.indices(shape)
    odd = ((k + j + i) % 2 == 1).ravel()
    best[(solid < 0.5) | ((solid == 0.5) & odd)] = 0
    truth = best.reshape(shape).astype(np.uint32)
    solid = solid.reshape(shape)
    lo, hi = (float(v) for v in a.grain_contrast.split(","))
    if not (0 < lo <= hi <= 1):
        raise SystemExit("--grain-contrast: 0 < LO <= HI <= 1")
    bright = solid
    if (lo, hi) != (1.0, 1.0) or a.dim_grains:
        rng_c = np.random.default_rng(a.seed + 7919)
        by_grain = rng_c.uniform(lo, hi, max(g[1] for g in grains) + 1)
        if a.dim_grains:
            frac, level = (float(v) for v in a.dim_grains.split(","))
            if not (0 <= frac <= 1 and 0 < level <= 1):
                raise SystemExit("--dim-grains: 0 <= FRAC <= 1, 0 < LEVEL <= 1")
            by_grain[rng_c.random(len(by_grain)) < frac] = level
        share = np.concatenate([[0.0], [by_grain[g[1]] for g in grains]])
        bright = share[blocks].mean(1).reshape(shape)
    grey = ndimage.gaussian_filter(10000 + 20000 * bright, [a.psf / zs, a.psf, a.psf])
    grey += rng.normal(0, 20000 / a.cnr, shape)
    with h5py.File(a.output + ".h5", "w") as f:
        f.create_dataset("scan", data=np.clip(np.rint(grey), 0, 65535).astype(np.uint16))
        f.create_dataset("labels", data=truth)
        f.attrs["voxel_size_m"] = np.array([12.3e-6 * zs, 12.3e-6, 12.3e-6])
    counts = np.bincount(truth.ravel(), minlength=len(grains) + 1)
    border = np.zeros(len(grains) + 1, bool)
    for axis in range(3):
        for end in (0, -1):
            border[np.unique(np.take(truth, end, axis=axis))] = True
    with open(a.output + "_truth.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["label", "volume_vox", "parent", "kind", "touches_border", "pores", "radius_vox", "cz", "cy", "cx"])
        for lab, gid, kind, r, c in grains:
            if counts[lab]:
                w.writerow([lab, counts[lab], gid, kind, int(border[lab]), 0, f"{r:.3f}",
                            f"{c[0] / zs:.2f}", f"{c[1]:.2f}", f"{c[2]:.2f}"])
    print(f"{len(placed)} grains, {int((counts[1:] > 0).sum())} particles, solid {solid.mean():.3f}")


if __name__ == "__main__":
    main()

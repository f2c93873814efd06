#!/usr/bin/env python3
"""Fast packing of N spheres in the oedometer's cylinder, for DEM benches at
10^4-10^6 spheres (pluviation is far too slow there): every sphere rests on
the layer below, so contacts exist from the first step.

Method (a deposit on a jittered lattice, computed, not simulated):
  * diameters ~ normal(d50, sigma) truncated at +-3 sigma, sigma from Cu as
    `tomograin dem pack` draws them (dem/pluviation.cpp, sigma_from_cu);
  * sites: triangular layers in ABC (fcc) order, in-plane spacing
    s = d_max + 2 sqrt(2) j (d_max = d50 + 3 sigma), each site moved by a
    uniform jitter in [-j, j]^2, so spheres of one layer never overlap;
  * layer 0 lies on the bottom platen (z = r); a sphere of layer k > 0 is
    lowered onto its pocket of layer k - 1: its height is the largest
    z_b + sqrt((r + r_b)^2 - d_xy^2) over the spheres b below within reach,
    i.e. it touches the support that stops it first (no overlap with any);
    a site with no support below (cut by the cylinder) stays empty;
  * sites whose sphere would cross the cylinder (radius R) are left out;
  * the N lowest spheres are kept (a nearly flat top).
Every pair is then checked with a k-d tree (scipy.spatial.cKDTree):
overlap <= 1e-9 of the smaller radius (rounding), or the script fails.

The cylinder radius is chosen so that the specimen's height is --aspect x its
diameter (the study's cell: 12.25 mm / 15 mm = 0.817). The study's grain
sizes are kept (so the study's time step 1e-7 s stays valid); the cell
grows with N.

Usage: lattice_packing.py N out.csv [--d50 1.36e-3] [--cu 1.07] [--jitter 0.03e-3]
                                 [--aspect 0.817] [--seed 1]
Writes x_m,y_m,z_m,r_m (metres, axis z, bottom z = 0: dem/packing_io.hpp) and
prints one line: N, cylinder radius, H0 (top of the highest sphere), porosity,
touching pairs (key=value).
"""
import argparse
import math
import sys

import numpy as np
from scipy.spatial import cKDTree


def sigma_from_cu(d50, cu):
    """Normal law's sigma from D50 and Cu = D60/D10 (dem/pluviation.cpp)."""
    return (cu - 1) * d50 / (0.2533 + 1.2816 * cu)


def lattice_packing(n, d50, cu, jitter, aspect, seed, radius=None):
    rng = np.random.default_rng(seed)
    sig = sigma_from_cu(d50, cu)
    dmax = d50 + 3 * sig
    rmax = dmax / 2
    s = dmax + 2 * math.sqrt(2) * jitter + 1e-9  # in-plane spacing: no overlap within a layer
    if radius is None:
        # Solid fraction of this deposit is ~0.6 (measured below); size R so
        # that N spheres give height ~ aspect * 2R.
        vs = n * math.pi / 6 * (d50**3 + 3 * d50 * sig**2)
        radius = (vs / (0.55 * math.pi * 2 * aspect)) ** (1 / 3) + dmax
    R = radius
    # Triangular lattice sites inside the cylinder (margin for jitter + rmax).
    rlim = R - rmax - math.sqrt(2) * jitter - 1e-9
    m = int(math.ceil(R / s)) + 2
    ii, jj = np.meshgrid(np.arange(-m, m + 1), np.arange(-m, m + 1), indexing="ij")
    bx = (ii + 0.5 * jj).ravel() * s
    by = (jj * math.sqrt(3) / 2).ravel() * s
    shifts = [(0.0, 0.0), (s / 2, s / (2 * math.sqrt(3))), (s, s / math.sqrt(3))]  # A, B, C
    xs, ys, zs, rs = [], [], [], []
    prev = None  # (x, y, z, r) of the layer below
    total, layer = 0, 0
    while total < n + 1:
        ox, oy = shifts[layer % 3]
        x0, y0 = bx + ox, by + oy
        keep = np.hypot(x0, y0) <= rlim
        x0, y0 = x0[keep], y0[keep]
        k = x0.size
        x = x0 + rng.uniform(-jitter, jitter, k)
        y = y0 + rng.uniform(-jitter, jitter, k)
        d = rng.normal(d50, sig, k)
        bad = np.abs(d - d50) > 3 * sig
        while bad.any():  # truncate at +-3 sigma, as the pluviation does
            d[bad] = rng.normal(d50, sig, int(bad.sum()))
            bad = np.abs(d - d50) > 3 * sig
        r = d / 2
        if prev is None:
            z = r.copy()
        else:
            px, py, pz, pr = prev
            tree = cKDTree(np.column_stack([px, py]))
            z = np.full(k, -np.inf)
            # Supports: spheres below within lateral reach r + r_b < r + rmax.
            for a, nb in enumerate(tree.query_ball_point(np.column_stack([x, y]), r + rmax)):
                for b in nb:
                    dxy2 = (x[a] - px[b]) ** 2 + (y[a] - py[b]) ** 2
                    c = r[a] + pr[b]
                    if dxy2 < c * c:
                        z[a] = max(z[a], pz[b] + math.sqrt(c * c - dxy2))
            ok = np.isfinite(z)
            x, y, z, r = x[ok], y[ok], z[ok], r[ok]
        xs.append(x), ys.append(y), zs.append(z), rs.append(r)
        prev = (x, y, z, r)
        total += x.size
        layer += 1
        if layer > 100000:
            raise SystemExit("lattice_packing.py: no layer grows; cylinder too small")
    x, y, z, r = (np.concatenate(v) for v in (xs, ys, zs, rs))
    order = np.argsort(z + r, kind="stable")[:n]
    order.sort()  # keep the build order (layer by layer)
    return R, x[order], y[order], z[order], r[order]


def check_no_overlap(x, y, z, r, R):
    pts = np.column_stack([x, y, z])
    tree = cKDTree(pts)
    pairs = tree.query_pairs(2 * r.max(), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    dist = np.linalg.norm(pts[i] - pts[j], axis=1)
    ov = (r[i] + r[j] - dist) / np.minimum(r[i], r[j])
    touching = ov > -1e-9
    if (ov > 1e-9).any():
        raise SystemExit("lattice_packing.py: overlap %.3g of the smaller radius (bug)" % ov.max())
    if (np.hypot(x, y) + r > R * (1 + 1e-12)).any() or (z < r * (1 - 1e-12)).any():
        raise SystemExit("lattice_packing.py: a sphere crosses the cylinder or the bottom (bug)")
    return int(touching.sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("n", type=int, help="number of spheres")
    ap.add_argument("out", help="packing CSV to write (x_m,y_m,z_m,r_m)")
    ap.add_argument("--d50", type=float, default=1.36e-3, help="median diameter, m (study: 1.36e-3)")
    ap.add_argument("--cu", type=float, default=1.07, help="uniformity coefficient D60/D10 (study: 1.07)")
    ap.add_argument("--jitter", type=float, default=0.03e-3, help="in-plane jitter half-width of the sites, m")
    ap.add_argument("--aspect", type=float, default=12.25 / 15, help="height / diameter of the specimen")
    ap.add_argument("--radius", type=float, default=None, help="cylinder radius, m (default: from N and --aspect)")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    if a.n < 1 or a.d50 <= 0 or a.cu < 1 or a.jitter < 0 or a.aspect <= 0:
        print("lattice_packing.py: need N >= 1, d50 > 0, cu >= 1, jitter >= 0, aspect > 0", file=sys.stderr)
        sys.exit(2)
    R, x, y, z, r = lattice_packing(a.n, a.d50, a.cu, a.jitter, a.aspect, a.seed, a.radius)
    contacts = check_no_overlap(x, y, z, r, R)
    h0 = float((z + r).max())
    por = 1 - float((4 / 3 * math.pi * r**3).sum()) / (math.pi * R * R * h0)
    tmp = a.out + ".tmp"
    with open(tmp, "w") as f:
        f.write("x_m,y_m,z_m,r_m\n")
        np.savetxt(f, np.column_stack([x, y, z, r]), fmt="%.17g", delimiter=",")
    import os

    os.replace(tmp, a.out)
    print("lattice_packing: spheres=%d radius_m=%r H0_m=%r porosity=%.4f touching_pairs=%d (%.3f per sphere)"
          % (x.size, R, h0, por, contacts, contacts / x.size))


if __name__ == "__main__":
    main()

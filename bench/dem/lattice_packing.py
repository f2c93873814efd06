#!/usr/bin/env python3
"""Fast packing of N spheres in the oedometer's cylinder, for DEM benches at
10^4-10^6 spheres (pluviation is far too slow there): every sphere rests on
the layer below, most of them on three spheres, so a contact network exists
from the first step (about 2.2 touching pairs a sphere, coordination ~4.5).

Method (a deposit on a jittered lattice, computed, not simulated):
  * diameters ~ normal(d50, sigma) truncated at +-3 sigma, sigma from Cu as
    `tomograin dem pack` draws them (dem/pluviation.cpp, sigma_from_cu);
  * sites: triangular layers in ABC (fcc) order, in-plane spacing
    s = d_max + 2 sqrt(2) j + margin (d_max = d50 + 3 sigma), each site
    moved by a uniform jitter in [-j, j]^2;
  * layer 0 lies on the bottom platen (z = r); a sphere of layer k > 0 sits
    in the pocket of the three spheres of layer k - 1 nearest its site,
    touching all three (trilateration), where that point exists and is near
    the site; else it is lowered straight down onto the sphere that stops it
    first (three layers below are checked; one that falls past two layers
    is left out); a site with nothing below stays
    empty; a pocket point that would cut a fourth sphere is raised until it
    only touches it; of two spheres of one layer that overlap after these
    shifts the later is left out;
  * sites whose sphere would cross the cylinder (radius R) are left out;
  * the N lowest spheres are kept (a nearly flat top).
Supports are placed closer than touching by the Hertz overlap that carries
the weight of the layers above (a few nm at the top, ~0.1 um at the bottom
of 10^6 spheres), so the contact network starts near equilibrium under
gravity. Every pair is then checked with a k-d tree (scipy.spatial.cKDTree):
overlap <= 2e-4 d50, or the script fails.

The cylinder radius is chosen so that the specimen's height is about
--aspect x its diameter (the study's cell: 12.25 mm / 15 mm = 0.817). The
study's grain sizes are kept (so the study's time step 1e-7 s stays valid);
the cell grows with N.

Usage: lattice_packing.py N out.csv [--d50 1.36e-3] [--cu 1.07] [--jitter 0.03e-3]
                                 [--margin 0.15e-3] [--aspect 0.817] [--radius R] [--seed 1]
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


def trilaterate(c1, c2, c3, d1, d2, d3):
    """Points at distances d1, d2, d3 from the centres c1, c2, c3 (arrays of
    shape (k, 3)), on the upper side (+z) of their plane; NaN where none."""
    ex = c2 - c1
    d = np.linalg.norm(ex, axis=1)
    ex /= d[:, None]
    v3 = c3 - c1
    i = np.einsum("ij,ij->i", ex, v3)
    ey = v3 - i[:, None] * ex
    j = np.linalg.norm(ey, axis=1)
    ey /= j[:, None]
    ez = np.cross(ex, ey)
    ez *= np.sign(ez[:, 2])[:, None]  # upwards (supports of one layer: ez.z != 0)
    px = (d1**2 - d2**2 + d**2) / (2 * d)
    py = (d1**2 - d3**2 + i**2 + j**2) / (2 * j) - i / j * px
    h2 = d1**2 - px**2 - py**2
    pz = np.sqrt(np.where(h2 > 0, h2, np.nan))
    return c1 + px[:, None] * ex + py[:, None] * ey + pz[:, None] * ez


def rest_on_layer(below, x, y, r, rmax, overlap=0.0):
    """Spheres of radii r over the sites (x, y) rest on the layer below
    (below[0] = its x, y, z, r; below[1], below[2] the ones under it, when
    they exist): each in the pocket of its three nearest spheres
    below, touching all three (trilateration), where that point exists and
    keeps clear of every other sphere below; else lowered straight down onto
    the support that stops it first; else (nothing below) left out."""
    px, py, pz, pr = below[0]
    tree = cKDTree(np.column_stack([px, py]))
    k = x.size
    _, nb = tree.query(np.column_stack([x, y]), k=3)
    centres = np.column_stack([px, py, pz])
    c = [centres[nb[:, q]] for q in range(3)]
    pt = trilaterate(c[0], c[1], c[2], *(r + pr[nb[:, q]] - overlap for q in range(3)))
    # The pocket must lie over the triangle's interior (a stable tripod) and
    # near the site (else the three nearest are not a pocket).
    ok = np.isfinite(pt).all(axis=1) & (np.hypot(pt[:, 0] - x, pt[:, 1] - y) < 0.5 * rmax)
    xo, yo, zo = np.where(ok, pt[:, 0], x), np.where(ok, pt[:, 1], y), np.where(ok, pt[:, 2], -np.inf)
    # Straight down where there is no pocket; and every sphere of the three
    # layers below within reach is checked (over holes a sphere can fall
    # past a layer): a pocket point that would cut a fourth sphere is raised
    # until it only touches it.
    if len(below) > 1:
        px, py, pz, pr = (np.concatenate(u) for u in zip(*below))
        tree = cKDTree(np.column_stack([px, py]))
    for a, cand in enumerate(tree.query_ball_point(np.column_stack([xo, yo]), r + rmax)):
        zmin = zo[a]
        for b in cand:
            dxy2 = (xo[a] - px[b]) ** 2 + (yo[a] - py[b]) ** 2
            cc = r[a] + pr[b] - overlap
            if dxy2 < cc * cc:
                zmin = max(zmin, pz[b] + math.sqrt(cc * cc - dxy2))
        zo[a] = zmin
    # A sphere that fell below the second layer down (holes in two layers
    # over one spot) is left out: it could reach layers not checked here.
    keep = np.isfinite(zo) & (zo >= (below[1][2].min() if len(below) > 1 else -np.inf))
    xo, yo, zo, r = xo[keep], yo[keep], zo[keep], r[keep]
    # Pockets shift the spheres in the plane (by ~0.05 mm): of two spheres of
    # this layer that would overlap, the later is left out.
    pts = np.column_stack([xo, yo, zo])
    pairs = cKDTree(pts).query_pairs(2 * rmax, output_type="ndarray")
    drop = np.zeros(xo.size, bool)
    if pairs.size:
        pairs = pairs[np.argsort(pairs[:, 0] * xo.size + pairs[:, 1])]
        dist = np.linalg.norm(pts[pairs[:, 0]] - pts[pairs[:, 1]], axis=1)
        for (a, b), dd in zip(pairs, dist):
            if dd < r[a] + r[b] and not drop[a]:
                drop[b] = True
    keep = ~drop
    return xo[keep], yo[keep], zo[keep], r[keep]


def lattice_packing(n, d50, cu, jitter, aspect, seed, radius=None, margin=0.15e-3, gravity_overlap=True):
    rng = np.random.default_rng(seed)
    sig = sigma_from_cu(d50, cu)
    dmax = d50 + 3 * sig
    rmax = dmax / 2
    # In-plane spacing: no overlap within a layer of sites, plus room for
    # the pockets' shifts (with 0.15 mm, ~4 % of the sites are left out).
    s = dmax + 2 * math.sqrt(2) * jitter + margin
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
    # Overlaps that carry the weight above (gravity_overlap): a sphere with
    # j layers over it presses on its three supports with about
    # (j + 1) m g / (3 cos 47 deg) each (the pocket's angle, vertical offset
    # 0.93 mm over r + r_b = 1.36 mm), and Hertz gives the overlap
    # delta = (F / (4/3 E* sqrt(R*)))^(2/3) (Table 1: E* = 2.93 GPa, R* = d50/4;
    # against the bottom platen F = (j + 1) m g, R* = d50/2). The layer count
    # is estimated from the sites of one layer (96 % of them kept).
    sites = int((np.hypot(bx, by) <= rlim).sum())
    layers_est = max(1, math.ceil(n / (0.96 * sites)))
    mg = 2180 * math.pi / 6 * d50**3 * 9.81
    estar = 5.5e9 / (2 * (1 - 0.25**2))

    def weight_overlap(layer, wall=False):
        if not gravity_overlap:
            return 0.0
        above = max(1, layers_est - layer)
        f = above * mg if wall else above * mg / (3 * 0.68)
        rstar = d50 / 2 if wall else d50 / 4
        return (f / (4 / 3 * estar * math.sqrt(rstar))) ** (2 / 3)

    xs, ys, zs, rs = [], [], [], []
    below = []  # (x, y, z, r) of the last three layers, the latest first
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
        if not below:
            z = r - weight_overlap(0, wall=True)
        else:
            x, y, z, r = rest_on_layer(below, x, y, r, rmax, weight_overlap(layer))
        xs.append(x), ys.append(y), zs.append(z), rs.append(r)
        below = [(x, y, z, r)] + below[:2]
        total += x.size
        layer += 1
        if layer > 100000:
            raise SystemExit("lattice_packing.py: no layer grows; cylinder too small")
    x, y, z, r = (np.concatenate(v) for v in (xs, ys, zs, rs))
    order = np.argsort(z + r, kind="stable")[:n]
    order.sort()  # keep the build order (layer by layer)
    return R, x[order], y[order], z[order], r[order]


def check_overlaps(x, y, z, r, R, overlap):
    pts = np.column_stack([x, y, z])
    tree = cKDTree(pts)
    pairs = tree.query_pairs(2 * r.max(), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    dist = np.linalg.norm(pts[i] - pts[j], axis=1)
    ov = (r[i] + r[j] - dist) / np.minimum(r[i], r[j])
    touching = ov > -1e-9
    if (ov > 1e-9 + overlap / np.minimum(r[i], r[j])).any():
        raise SystemExit("lattice_packing.py: overlap %.3g of the smaller radius (bug)" % ov.max())
    if (np.hypot(x, y) + r > R * (1 + 1e-12)).any() or (z < r - overlap * (1 + 1e-6)).any():
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
    ap.add_argument("--margin", type=float, default=0.15e-3,
                    help="in-plane spacing of the sites beyond d_max + 2 sqrt(2) jitter, m (room for the pockets' shifts)")
    ap.add_argument("--no-overlap", action="store_true",
                    help="spheres just touch their supports (default: overlaps that carry the weight above)")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    if a.n < 1 or a.d50 <= 0 or a.cu < 1 or a.jitter < 0 or a.aspect <= 0:
        print("lattice_packing.py: need N >= 1, d50 > 0, cu >= 1, jitter >= 0, aspect > 0", file=sys.stderr)
        sys.exit(2)
    R, x, y, z, r = lattice_packing(a.n, a.d50, a.cu, a.jitter, a.aspect, a.seed, a.radius, a.margin, not a.no_overlap)
    contacts = check_overlaps(x, y, z, r, R, 2e-4 * a.d50)  # the largest weight overlap: ~1e-4 d50 at 10^6
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

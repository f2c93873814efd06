#!/usr/bin/python3
"""An independent ("blind") synthetic XCT scan of a dense sand with exact truth.

Written for issue 19 without any code, parameter or idea taken from
data_synth, so that tomograin's segmentation can be measured on scans it was
not tuned on. Everything is in voxels; voxel (k,j,i) covers
[k,k+1)x[j,j+1)x[i,i+1) in (z,y,x), so its centre is (k+0.5, j+0.5, i+0.5).

Method
  1. Packing: grain radii r ~ N(R, spread R) (clipped to [0.6R, 1.5R], --radius-range) are
     drawn until their volume is --phi of a periodic box one grain larger
     than the scan on each side; centres uniform at random; then collective
     overlap removal (each overlapping pair pushed apart along its axis by
     half its overlap, repeated until every overlap is < 0.05 voxel or
     0.2 % of R; periodic, so grains at the scan faces are as dense as
     inside). Grains are "touching" in the sense of sand: most neighbours sit
     within a fraction of a voxel. Grains cut by the scan faces are kept.
  2. Shapes: a slightly ellipsoidal (axes x U(0.92,1.08), random
     orientation), slightly bumpy (three odd cubic lobes, +-3 %) star-shaped
     body, described by the approximate signed distance d = |v| - r(v/|v|).
     With --angularity A > 0 (crushed, faceted sand) each body is intersected
     with K = 12 half-spaces n_k . v <= h_k in the grain's own frame (random
     unit normals n_k, h_k = r0 (1 - A U(0,1))): d = max(|v| - r(v/|v|),
     max_k (n_k . v - h_k)), flat facets with sharp edges and corners; the
     facets move with a split grain's halves. The packing still places the
     unfaceted bodies, so faceting only removes solid: angular packings are
     looser (lower solid fraction) than A = 0 ones. A = 0 draws no facet
     random numbers (scenes identical to those before the option).
     A split grain (--split-frac) is cut by a random plane through
     c + U(-0.15,0.15) R n; the gap (--gap voxels) is centred on the plane;
     each half moves --drift/2 voxels away along n (translation only, no
     rotation). A chipped grain (--chip-frac) loses the cap beyond a plane at
     U(0.6,0.85) r from its centre (r = r0; with facets the smaller of r0
     and the distance along n to the first facet plane, so that a facet does
     not remove the whole cap); the chip is KEPT as a separate particle (kind
     chip) with the gap centred on the cut plane. 2-5 spherical pores per
     grain, radius U(--pores), fully inside (1.5 voxels clear of the star
     body's inscribed sphere and of every facet plane), apart from each other
     and at least 3 voxels from any cut.
  3. Partial volume: the signed distance at each voxel centre in the
     particle's bounding box; voxels within 1 voxel of a surface are
     supersampled (--supersample s per axis, each sample's cover
     clip(0.5 - d s, 0, 1), i.e. a linear ramp one sample wide: a plane cut
     integrates exactly). Particles are rendered one by one in their boxes;
     where two overlap (contacts, at most a small lens) the solid fraction is
     min(1, sum) and the truth label is the particle covering most of the
     voxel. Truth: label where the filled cover (pores counted as the
     grain's) >= 0.5, else 0.
  4. Imaging: grey = void + (solid - void) * blur_psf(solid fraction) *
     cupping(rho) + N(0, (solid - void) / cnr); void 10000, solid 30000;
     with --noise-corr c the noise is white noise smoothed by a Gaussian of
     sigma c voxels and rescaled to the same per-voxel sigma;
     cupping(rho) = 1 - c (1 - (rho/rho_max)^2) for rho < rho_max (radial from
     the scan's z axis, rho_max half the smaller of nx, ny; 1 beyond): the
     contrast at the centre is (1 - c) of that at the border. With
     --grain-contrast LO,HI each grain (its fragments alike) has its own
     attenuation: its solid fraction counts U(LO, HI) times (a natural sand's
     grains differ in density and mineralogy; where two grains' voxels
     overlap, the cover-weighted mean); drawn from seed + 2000, so scenes
     without the option are unchanged. With --grain-texture A the solid's
     attenuation varies inside the grains too (microporosity, inclusions):
     times 1 + A g, g a unit-variance Gaussian field correlated over
     --texture-length voxels (white noise smoothed, seed + 3000). With
     --rings A,P ring artefacts (a detector element off in every projection):
     each whole radius from the slices' centre gets, with probability P, an
     offset N(0, A x contrast), the same on every slice, added after the
     blur (seed + 4000). Gaussian blur
     with scipy.ndimage (mode nearest at the faces). Rounded, clipped to
     uint16.

Outputs
  PREFIX.h5     /scan (uint16, zyx), /labels (uint32 truth, 0 void); attrs
                voxel_size_m (1e-5, nominal: everything is in voxels) and
                blind_scene (the JSON below)
  PREFIX_truth.csv  label, volume_vox (truth voxels), parent (grain id),
                kind (intact | half | chipped | chip | shell), touches_border (0/1),
                pores (count), radius_vox (grain's r0), cz, cy, cx (centre of
                the grain, voxels)
  PREFIX.json   parameters, counts by kind, solid fraction, measured CNR,
                measured split gaps (noiseless, unblurred), timings
  PREFIX.tif    the scan as a TIFF (with --tif; scikit-image peer input)

Complexity: O(N_particles * box^3) for the centre pass plus
O(shell * s^3) samples; a 192^3 scene with R 20 takes ~9 s CPU (one core).
Reference for the overlap-removal packing: W. S. Jodrey and E. M. Tory,
"Computer simulation of close random packing of equal spheres", Phys. Rev. A
32 (1985) 2347, doi:10.1103/PhysRevA.32.2347 (here without the shrinking
outer diameter: the target fraction is fixed, overlaps are relaxed).
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

VOID, SOLID = 10000.0, 30000.0
SHELL = 1.0           # voxels: a centre closer than this to a surface is supersampled (> sqrt(3)/2)
PORE_CLEAR = 3.0      # voxels between a pore and a cut plane's gap
FACETS = 12           # facet planes per grain with --angularity > 0


def parse_size(s):
    p = [int(v) for v in s.split(",")]
    if len(p) == 1:
        p = p * 3
    if len(p) != 3 or min(p) < 8:
        raise argparse.ArgumentTypeError("--size is N or nz,ny,nx (>= 8)")
    return tuple(p)


def draw_grain_contrast(ids, lohi, seed):
    """Grain id -> its contrast factor, U(lohi) (--grain-contrast), from its own
    generator (seed + 2000) so that scenes and series without it are unchanged;
    None when all grains are alike (1, 1)."""
    if tuple(lohi) == (1.0, 1.0):
        return None
    ids = sorted(ids)
    return dict(zip(ids, np.random.default_rng(seed + 2000).uniform(*lohi, size=len(ids)).tolist()))


def parse_rings(s):
    p = [float(v) for v in s.split(",")]
    if len(p) != 2 or p[0] < 0 or not 0 <= p[1] <= 1:
        raise argparse.ArgumentTypeError("--rings is A,P: amplitude >= 0 (x contrast), share of radii in 0..1")
    return tuple(p)


def parse_range(s):
    a, b = (float(v) for v in s.split(","))
    if not 0 < a <= b:
        raise argparse.ArgumentTypeError("a range is LO,HI with 0 < LO <= HI")
    return a, b


def random_unit(rng, n=None):
    v = rng.normal(size=(3,) if n is None else (n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def radial(shapes, idx, u):
    """Radius of grains idx along unit directions u (m, 3)."""
    q = np.einsum("mi,mij,mj->m", u, shapes["A"][idx], u)
    lob = np.einsum("mij,mj->mi", shapes["lobes"][idx], u)
    bump = 1.0 + np.einsum("mi,mi->m", lob ** 3, shapes["amps"][idx])
    return shapes["r0"][idx] * bump / np.sqrt(q)


def pack(rng, shape, R, spread, phi, pad_frac, pad, elongation=1.0, angularity=0.0, radius_range=(0.6, 1.5)):
    """Centres (volume coordinates), shapes and a uniform draw u per grain
    of a dense random packing. The overlap of a pair is measured with each
    grain's radius along the line of centres (its shape, not a bounding
    sphere), so contacts are contacts and not fused lenses. Grains with
    u < pad_frac (the ones to be split) get pad more reach while relaxing,
    room for their halves' drift. Facets (angularity > 0) are not seen by
    the packing: it places the unfaceted bodies."""
    rmax = radius_range[1] * R
    margin = rmax * 1.1 * elongation ** (2 / 3) + 2.0 if elongation != 1.0 else rmax + 2.0
    L = np.array(shape, float) + 2 * margin
    target = phi * float(np.prod(L))
    radii = []
    vol = 0.0
    while vol < target:
        r = float(np.clip(rng.normal(R, spread * R), radius_range[0] * R, rmax))
        radii.append(r)
        vol += 4.0 / 3.0 * math.pi * r ** 3
    r = np.array(radii)
    n = r.size
    shapes = [make_shape(rng, rr, elongation, angularity) for rr in r]
    shapes = {k: np.array([sh[k] for sh in shapes]) for k in shapes[0]}
    u = rng.uniform(size=n)
    extra = np.where(u < pad_frac, pad, 0.0)
    reach = shapes["rmax"] + extra
    pos = rng.uniform(0, 1, size=(n, 3)) * L
    tol = min(0.05, 0.002 * R)
    it = 0
    worst = float("inf")
    for it in range(1, 5001):
        tree = cKDTree(pos, boxsize=L)
        pairs = tree.query_pairs(2 * reach.max(), output_type="ndarray")
        if pairs.size == 0:
            worst = 0.0
            break
        i, j = pairs[:, 0], pairs[:, 1]
        dv = pos[j] - pos[i]
        dv -= L * np.round(dv / L)
        dist = np.linalg.norm(dv, axis=1)
        near = dist < reach[i] + reach[j]
        i, j, dv, dist = i[near], j[near], dv[near], np.maximum(dist[near], 1e-9)
        e = dv / dist[:, None]
        ov = radial(shapes, i, e) + radial(shapes, j, -e) + extra[i] + extra[j] - dist
        keep = ov > 0
        worst = float(ov.max()) if ov.size else 0.0
        if worst < tol:
            break
        i, j, e, ov = i[keep], j[keep], e[keep], ov[keep]
        step = e * (0.5 * ov + 0.5 * tol)[:, None]
        disp = np.zeros_like(pos)
        np.add.at(disp, i, -step)
        np.add.at(disp, j, step)
        # a grain in many contacts moves by the mean push (stable), not the sum
        cnt = np.bincount(np.concatenate([i, j]), minlength=n).astype(float)
        pos = (pos + disp / np.maximum(cnt, 1)[:, None]) % L
    centres = pos - margin
    return centres, shapes, u, {"iterations": it, "max_overlap_vox": worst, "grains_in_box": int(n),
                                "box_solid_fraction": float(vol / np.prod(L))}


def make_shape(rng, r0, elongation=1.0, angularity=0.0):
    """A near-sphere: ellipsoid axes r0 x U(0.92, 1.08), random orientation,
    three odd cubic lobes of total amplitude 3 %. With elongation e > 1 the
    first axis is e times the other two at the same volume (a prolate grain,
    e.g. 1.6 for an elongated sand): axes x (e^(2/3), e^(-1/3), e^(-1/3)).
    With angularity A > 0, FACETS planes (unit normals fn, distances from the
    centre fh = r0 (1 - A U(0,1))) cut the body; A = 0 draws nothing more
    (fn, fh empty)."""
    ax = rng.uniform(0.92, 1.08, 3) * np.array([elongation ** (2 / 3), elongation ** (-1 / 3), elongation ** (-1 / 3)])
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    A = Q @ np.diag(1.0 / ax ** 2) @ Q.T
    amps = rng.uniform(-1, 1, 3)
    amps *= 0.03 / max(np.abs(amps).sum(), 1e-9)
    sh = {"r0": r0, "A": A, "lobes": random_unit(rng, 3), "amps": amps,
          "rmin": r0 * ax.min() * 0.97, "rmax": r0 * ax.max() * 1.03}
    if angularity > 0:
        sh["fn"] = random_unit(rng, FACETS)
        sh["fh"] = r0 * (1.0 - angularity * rng.uniform(size=FACETS))
    else:
        sh["fn"], sh["fh"] = np.zeros((0, 3)), np.zeros(0)
    return sh


def facet_distance(g, x):
    """max_k (n_k . x - h_k) over the grain's facet planes, x (..., 3)
    relative to the grain centre: the signed distance of the facets'
    intersection (exact inside; a lower bound outside, beyond edges and
    corners). Only for grains with facets."""
    return (x @ g["fn"].T - g["fh"]).max(axis=-1)


def facet_ray(g, n):
    """Distance from the grain centre along unit n to the first facet
    plane (inf without facets)."""
    c = g["fn"].astype(np.float64) @ n
    up = c > 1e-9
    return float(np.min(g["fh"][up] / c[up])) if up.any() else math.inf


class Particle:
    """One solid piece: a grain body (faceted with --angularity),
    intersected with half-spaces, minus pores. d(p) is an approximate signed
    distance (negative inside)."""

    def __init__(self, grain, kind, cuts, shift):
        self.g = grain          # dict: c, r0, A, lobes, amps, pores, id
        self.kind = kind
        # list of (n, offset, side, gap/2): side*(n.v - offset) >= gap/2 is kept
        self.cuts = [(np.asarray(n, np.float32), np.float32(o), np.float32(s), np.float32(h)) for n, o, s, h in cuts]
        self.shift = shift      # rigid translation of this piece (drift)
        self.pores = []         # (centre relative to grain centre, radius)
        self.wall = 0.0         # > 0: a shell, the body hollowed to this thickness (voxels)
        self.label = 0

    def centre(self):
        return self.g["c"] + self.shift

    def d_filled(self, v):
        """v: (..., 3) float32, relative to the piece's (shifted) grain centre."""
        g = self.g
        x = v.reshape(-1, 3)
        d2 = np.einsum("ij,ij->i", x, x)
        np.maximum(d2, 1e-12, out=d2)
        y = x @ g["M"]                                   # (N, 6): A x and the three lobe projections
        q = np.einsum("ij,ij->i", y[:, :3], x)           # x.A.x = |x|^2 (u.A.u)
        inv = 1.0 / np.sqrt(d2)
        lob = y[:, 3:] * inv[:, None]
        bump = 1.0 + (lob * lob * lob) @ g["amps"]
        # |x| - r0 bump / sqrt(u.A.u), with sqrt(u.A.u) = sqrt(q) / |x|
        d = d2 * inv - g["r0"] * bump * np.sqrt(d2 / q)
        if len(g["fh"]):
            d = np.maximum(d, facet_distance(g, x))
        if self.wall > 0:  # hollow: only what lies within `wall` of the body's surface
            d = np.maximum(d, -(d + self.wall))
        for n, off, side, half_gap in self.cuts:
            d = np.maximum(d, half_gap - side * (x @ n - off))
        return d.reshape(v.shape[:-1])

    def d_solid(self, v, d):
        for pc, pr in self.pores:
            w = v - pc.astype(np.float32)
            d = np.maximum(d, pr - np.sqrt(np.einsum("...i,...i->...", w, w)))
        return d


def make_grain(gid, c, shapes, k):
    g = {key: shapes[key][k] for key in shapes}
    g.update(id=gid, c=c, amps=g["amps"].astype(np.float32),
             M=np.hstack([g["A"], g["lobes"].T]).astype(np.float32),
             fn=g["fn"].astype(np.float32), fh=g["fh"].astype(np.float32))
    return g


def place_pores(rng, g, planes, a):
    """2-5 pores inside the grain, clear of each other and of every cut plane
    (planes: list of (n, offset, half_gap) relative to the grain centre).
    Inside: within rmin - 1.5 voxels of the centre (rmin bounds the star body
    from below) and, with facets, 1.5 voxels inside every facet plane."""
    pores = []
    want = int(rng.integers(2, 6))
    for _ in range(200):
        if len(pores) == want:
            break
        pr = rng.uniform(*a.pores)
        reach = g["rmin"] - pr - 1.5
        if reach <= 0:
            continue
        p = random_unit(rng) * reach * rng.uniform(0, 1) ** (1 / 3)
        if len(g["fh"]) and facet_distance(g, p) > -(pr + 1.5):
            continue
        if any(abs(p @ n - off) < pr + hg + PORE_CLEAR for n, off, hg in planes):
            continue
        if any(np.linalg.norm(p - q) < pr + qr + 1.0 for q, qr in pores):
            continue
        pores.append((p, pr))
    return pores


def build(rng, a, shape):
    split_pad = a.drift / 2.0
    centres, shapes, kinds, pstats = pack(rng, shape, a.radius, a.spread, a.phi, a.split_frac, split_pad, a.elongation,
                                          a.angularity, a.radius_range)
    hi = np.array(shape, float)
    particles = []
    gid = 0
    srng = np.random.default_rng(a.seed + 5000)  # shells: their own draws, scenes without them unchanged
    for k in range(centres.shape[0]):
        c, r0 = centres[k], shapes["r0"][k]
        bound = shapes["rmax"][k] + split_pad + 1
        if np.any(c + bound < 0) or np.any(c - bound > hi):
            continue
        gid += 1
        g = make_grain(gid, c, shapes, k)
        hg = a.gap / 2.0
        if kinds[k] < a.split_frac:
            n = random_unit(rng)
            off = rng.uniform(-0.15, 0.15) * r0
            pores = place_pores(rng, g, [(n, off, hg)], a)
            for side in (1.0, -1.0):
                p = Particle(g, "half", [(n, off, side, hg)], side * split_pad * n)
                p.pores = [(pc, pr) for pc, pr in pores if side * (pc @ n - off) > 0]
                # pores are relative to the grain centre: they move with the piece
                particles.append(p)
        elif kinds[k] < a.split_frac + a.chip_frac:
            n = random_unit(rng)
            # the cap is measured on the faceted body: a facet nearer than r0 along n
            # would otherwise leave an empty or sliver chip
            off = rng.uniform(0.6, 0.85) * (min(r0, facet_ray(g, n)) if len(g["fh"]) else r0)
            pores = place_pores(rng, g, [(n, off, hg)], a)
            body = Particle(g, "chipped", [(n, off, -1.0, hg)], np.zeros(3))
            body.pores = [(pc, pr) for pc, pr in pores if pc @ n < off]
            particles.append(body)
            if a.chip_mode == "keep":
                chip = Particle(g, "chip", [(n, off, 1.0, hg)], np.zeros(3))
                chip.pores = [(pc, pr) for pc, pr in pores if pc @ n > off]
                particles.append(chip)
        elif a.shell_frac > 0 and srng.random() < a.shell_frac / max(1e-12, 1 - a.split_frac - a.chip_frac):
            # an open shell: the body hollowed to a wall U(--shell-wall) voxels thick, the cap beyond a
            # plane at U(-0.3, 0.3) r0 from the centre removed so that the hollow opens onto the void
            n = random_unit(srng)
            p = Particle(g, "shell", [(n, srng.uniform(-0.3, 0.3) * r0, -1.0, 0.0)], np.zeros(3))
            p.wall = float(srng.uniform(*a.shell_wall))
            place_pores(rng, g, [], a)  # drawn and dropped (a wall has none): the other grains' pores as without shells
            particles.append(p)
        else:
            p = Particle(g, "intact", [], np.zeros(3))
            p.pores = place_pores(rng, g, [], a)
            particles.append(p)
    return particles, pstats


def render(particles, shape, s, contrast=None):
    """Solid fraction (pores void), filled cover of the owner, owner label;
    with contrast (grain id -> factor) the solid fraction weighted by it."""
    solid = np.zeros(shape, np.float32)
    dens = np.zeros(shape, np.float32) if contrast else None
    filled = np.zeros(shape, np.float32)
    best = np.zeros(shape, np.float32)
    owner = np.zeros(shape, np.uint32)
    sub = (np.arange(s) + 0.5) / s - 0.5
    offs = np.stack(np.meshgrid(sub, sub, sub, indexing="ij"), -1).reshape(-1, 3).astype(np.float32)
    for lab, p in enumerate(particles, 1):
        p.label = lab
        c = p.centre()
        ext = p.g["rmax"] + 1.5
        lo = np.maximum(np.floor(c - ext).astype(int), 0)
        hi = np.minimum(np.ceil(c + ext).astype(int), shape)
        if np.any(hi <= lo):
            continue
        axes = [(np.arange(lo[i], hi[i]) + 0.5 - c[i]).astype(np.float32) for i in range(3)]
        v = np.stack(np.meshgrid(*axes, indexing="ij"), -1)
        df = p.d_filled(v)
        ds = p.d_solid(v, df)
        occ_f = (df < 0).astype(np.float32)
        occ_s = (ds < 0).astype(np.float32)
        shell = (np.abs(df) < SHELL) | (np.abs(ds) < SHELL)
        if shell.any():
            pts = v[shell][:, None, :] + offs[None, :, :]
            sf = p.d_filled(pts)
            ss = p.d_solid(pts, sf)
            occ_f[shell] = np.clip(0.5 - sf * s, 0, 1).mean(axis=1)
            occ_s[shell] = np.clip(0.5 - ss * s, 0, 1).mean(axis=1)
        box = tuple(slice(lo[i], hi[i]) for i in range(3))
        solid[box] += occ_s
        if dens is not None:
            dens[box] += occ_s * contrast[p.g["id"]]
        filled[box] += occ_f
        b = best[box]
        win = occ_f > b
        b[win] = occ_f[win]
        owner[box][win] = lab
    if dens is not None:
        over = solid > 1
        dens[over] /= solid[over]  # overlap lens: the mean of the grains' factors
    np.minimum(solid, 1, out=solid)
    truth = np.where(filled >= 0.5, owner, 0).astype(np.uint32)
    overlap = float(np.maximum(filled - 1, 0).sum() / max(float(filled.sum()), 1.0))
    return solid, truth, overlap, dens


def measure_gaps(solid, particles, a, rng):
    """Width of each split gap in the noiseless, unblurred solid fraction:
    the integral of (1 - solid) along the plane normal over a window of
    +-(gap/2 + drift/2 + 3) voxels, on lines through the plane within 0.4 r0
    of the axis, trilinear interpolation; only lines inside the scan. The
    window is pore free by construction (PORE_CLEAR). Expected: gap + drift."""
    out = []
    shape = np.array(solid.shape)
    seen = set()
    for p in particles:
        if p.kind != "half" or p.g["id"] in seen:
            continue
        seen.add(p.g["id"])
        n, off, _, hg = p.cuts[0]
        c = p.g["c"]
        w = hg + a.drift / 2.0 + 3.0
        t = np.arange(-w, w + 1e-9, 0.05)
        # in-plane offsets
        e1 = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        widths = []
        for _ in range(12):
            rr = 0.4 * p.g["r0"] * math.sqrt(rng.uniform())
            ang = rng.uniform(0, 2 * math.pi)
            base = c + off * n + rr * (math.cos(ang) * e1 + math.sin(ang) * e2)
            pts = base[None, :] + t[:, None] * n[None, :]   # the halves drift symmetrically about this plane
            if np.any(pts < 1) or np.any(pts > shape - 2):
                continue
            val = ndimage.map_coordinates(solid, (pts - 0.5).T, order=1)
            widths.append(float(np.sum(1 - val) * 0.05))
        if widths:
            out.append(float(np.median(widths)))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", required=True, help="output prefix (writes PREFIX.h5, PREFIX_truth.csv, PREFIX.json)")
    ap.add_argument("--size", type=parse_size, default=(192, 192, 192), help="scan size, voxels: N or nz,ny,nx (192)")
    ap.add_argument("--radius", type=float, default=20.0, help="mean grain radius, voxels (20)")
    ap.add_argument("--spread", type=float, default=0.12, help="relative standard deviation of the grain radii (0.12)")
    ap.add_argument("--radius-range", type=parse_range, default=(0.6, 1.5),
                    help="grain radii clipped to [LO R, HI R] (0.6,1.5; e.g. --spread 0.5 --radius-range 0.3,2 "
                         "for a crushed sand's wide size distribution)")
    ap.add_argument("--elongation", type=float, default=1.0,
                    help="long axis over the other two of every grain, same volume (1.0: near-spheres)")
    ap.add_argument("--angularity", type=float, default=0.0,
                    help="facet every grain with 12 random planes at r0 (1 - A U(0,1)) from its centre "
                         "(crushed, angular sand; 0 <= A <= 0.6; 0.0: no facets)")
    ap.add_argument("--phi", type=float, default=0.58, help="solid fraction of the packing before cuts and pores (0.58)")
    ap.add_argument("--gap", type=float, default=1.0, help="fragment gap width, voxels (1.0)")
    ap.add_argument("--split-frac", type=float, default=0.15, help="fraction of grains split in two halves (0.15)")
    ap.add_argument("--drift", type=float, default=0.0,
                    help="voxels the two halves of a split grain move apart along the plane normal, on top of the gap (0)")
    ap.add_argument("--chip-frac", type=float, default=0.05, help="fraction of grains with a cap chipped off (0.05)")
    ap.add_argument("--chip-mode", choices=("keep", "remove"), default="keep",
                    help="keep the chip as a separate particle a gap away, or remove it (keep)")
    ap.add_argument("--shell-frac", type=float, default=0.0,
                    help="fraction of the grains that are open shells (bioclasts: a hollow body, its wall "
                         "--shell-wall thick, opened by a plane cut; 0: none)")
    ap.add_argument("--shell-wall", type=parse_range, default=(2.0, 4.0),
                    help="min,max wall thickness of the shells, voxels (2,4)")
    ap.add_argument("--pores", type=parse_range, default=(1.0, 3.0),
                    help="min,max radius of the 2-5 internal spherical pores per grain, voxels (1,3)")
    ap.add_argument("--psf", type=float, default=0.7, help="Gaussian PSF sigma, voxels (0.7; 0 = none)")
    ap.add_argument("--cnr", type=float, default=13.0,
                    help="contrast-to-noise ratio: noise sigma = (solid - void)/cnr grey levels (13; 0 = no noise)")
    ap.add_argument("--noise-corr", type=float, default=0.0,
                    help="correlation length of the noise, voxels: white noise smoothed by a Gaussian of this sigma, "
                         "rescaled to the same per-voxel sigma (as reconstruction filters make it; 0 = white)")
    ap.add_argument("--grain-contrast", type=parse_range, default=(1.0, 1.0),
                    help="LO,HI: each grain's contrast over the void is U(LO,HI) of the solid's (grains of "
                         "different density; default 1,1: all alike)")
    ap.add_argument("--grain-texture", type=float, default=0.0,
                    help="relative amplitude (sd) of the attenuation's variation inside the grains (0: none)")
    ap.add_argument("--texture-length", type=float, default=2.0,
                    help="correlation length of that variation, voxels (2)")
    ap.add_argument("--rings", type=parse_rings, default=(0.0, 0.0),
                    help="A,P: ring artefacts, offset sd A x contrast on a share P of the radii (default none)")
    ap.add_argument("--cupping", type=float, default=0.0,
                    help="fraction of the contrast lost at the scan's axis relative to its border, radial (0)")
    ap.add_argument("--supersample", type=int, default=3, help="samples per axis for partial volume, near surfaces (3)")
    ap.add_argument("--seed", type=int, default=1, help="random seed (1)")
    ap.add_argument("--tif", action="store_true", help="also write PREFIX.tif (the scan; scikit-image peer input)")
    ap.add_argument("--no-measure", action="store_true", help="skip the CNR and gap measurements")
    a = ap.parse_args(argv)
    if not 0 < a.gap or a.split_frac + a.chip_frac + a.shell_frac > 1 or not 0 < a.shell_wall[0] or a.supersample < 1 or not 0 <= a.angularity <= 0.6:
        ap.error("need gap > 0, split-frac + chip-frac + shell-frac <= 1, shell walls > 0, supersample >= 1, 0 <= angularity <= 0.6")
    import h5py
    t0 = time.perf_counter()
    rng = np.random.default_rng(a.seed)
    shape = a.size
    particles, pstats = build(rng, a, shape)
    t_pack = time.perf_counter() - t0
    contrast = draw_grain_contrast({p.g["id"] for p in particles}, a.grain_contrast, a.seed)
    solid, truth, overlap, dens = render(particles, shape, a.supersample, contrast)
    t_render = time.perf_counter() - t0 - t_pack

    # truth table: consecutive labels for the particles that have voxels
    counts = np.bincount(truth.ravel(), minlength=len(particles) + 1)
    present = [p for p in particles if counts[p.label] > 0]
    lut = np.zeros(len(particles) + 1, np.uint32)
    for new, p in enumerate(present, 1):
        lut[p.label] = new
    truth = lut[truth]
    for p in present:
        p.label = int(lut[p.label])
    border = set()
    for face in (truth[0], truth[-1], truth[:, 0], truth[:, -1], truth[:, :, 0], truth[:, :, -1]):
        border.update(np.unique(face).tolist())
    counts = np.bincount(truth.ravel(), minlength=len(present) + 1)

    # imaging
    contrast = SOLID - VOID
    seen_solid = solid if dens is None else dens  # what the beam sees: each grain's own attenuation
    if a.grain_texture > 0:
        trng = np.random.default_rng(a.seed + 3000)
        tex = ndimage.gaussian_filter(trng.normal(0, 1, size=shape).astype(np.float32), a.texture_length, mode="wrap")
        tex /= tex.std()
        seen_solid = seen_solid * np.maximum(0, 1 + a.grain_texture * tex)
    img = ndimage.gaussian_filter(seen_solid, a.psf, mode="nearest") if a.psf > 0 else seen_solid.copy()
    if a.cupping > 0:
        ny, nx = shape[1], shape[2]
        y = np.arange(ny) + 0.5 - ny / 2
        x = np.arange(nx) + 0.5 - nx / 2
        rho = np.sqrt(y[:, None] ** 2 + x[None, :] ** 2) / (min(ny, nx) / 2)
        prof = (1 - a.cupping * (1 - np.minimum(rho, 1) ** 2)).astype(np.float32)
        img *= prof[None, :, :]
    img = img * contrast + VOID
    if a.rings[0] > 0:
        rrng = np.random.default_rng(a.seed + 4000)
        ny, nx = shape[1], shape[2]
        rad = np.sqrt((np.arange(ny) + 0.5 - ny / 2)[:, None] ** 2 + (np.arange(nx) + 0.5 - nx / 2)[None, :] ** 2)
        rad = rad.astype(int)
        off = np.where(rrng.random(rad.max() + 1) < a.rings[1], rrng.normal(0, a.rings[0] * contrast, rad.max() + 1), 0)
        img += off[rad].astype(np.float32)[None, :, :]
    sigma = contrast / a.cnr if a.cnr > 0 else 0.0
    if sigma > 0:
        noise = rng.normal(0, 1, size=shape).astype(np.float32)
        if a.noise_corr > 0:
            # smoothing lowers the per-voxel sigma; rescale so that the CNR stays the one asked for
            noise = ndimage.gaussian_filter(noise, a.noise_corr, mode="wrap")
            noise /= noise.std()
        img += sigma * noise
    scan = np.clip(np.rint(img), 0, 65535).astype(np.uint16)
    t_image = time.perf_counter() - t0 - t_pack - t_render

    info = {"generator": "bench/segmentation/blind_scene.py (independent of data_synth)",
            "params": {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(a).items()},
            "void_grey": VOID, "solid_grey": SOLID, "noise_sigma": sigma,
            "packing": pstats,
            "solid_fraction": float(solid.mean()),
            "filled_fraction": float((truth > 0).mean()),
            "overlap_fraction": overlap,
            "particles": len(present),
            "grains": len({p.g["id"] for p in present}),
            "by_kind": {k: sum(1 for p in present if p.kind == k) for k in ("intact", "half", "chipped", "chip", "shell")},
            "touching_border": len(border - {0})}
    if not a.no_measure:
        sd = ndimage.binary_erosion(solid >= 1.0, iterations=2)
        vd = ndimage.binary_erosion(solid <= 0.0, iterations=2)
        s16 = scan.astype(np.float64)
        if sd.any() and vd.any():
            ms, mv, sv = s16[sd].mean(), s16[vd].mean(), s16[vd].std()
            info["measured"] = {"solid_mean": ms, "void_mean": mv, "void_std": sv,
                                "cnr": (ms - mv) / sv if sv > 0 else None}
        gaps = measure_gaps(solid, particles, a, np.random.default_rng(a.seed + 1000))
        if gaps:
            info["measured_gap_vox"] = {"n": len(gaps), "expected": a.gap + a.drift, "median": float(np.median(gaps)),
                                        "min": float(np.min(gaps)), "max": float(np.max(gaps))}
    info["seconds"] = {"pack": t_pack, "render": t_render, "image": t_image}

    out = a.output
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    tmp = out + ".h5.part"
    with h5py.File(tmp, "w") as f:
        f.create_dataset("scan", data=scan)
        f.create_dataset("labels", data=truth, compression="gzip", compression_opts=1)
        f.attrs["voxel_size_m"] = np.array([1e-5, 1e-5, 1e-5])
        f.attrs["blind_scene"] = json.dumps(info)
    rows = ["label,volume_vox,parent,kind,touches_border,pores,radius_vox,cz,cy,cx"]
    for p in present:
        c = p.centre()
        rows.append(f"{p.label},{int(counts[p.label])},{p.g['id']},{p.kind},{int(p.label in border)},"
                    f"{len(p.pores)},{p.g['r0']:.3f},{c[0]:.3f},{c[1]:.3f},{c[2]:.3f}")
    with open(out + "_truth.csv.part", "w") as f:
        f.write("\n".join(rows) + "\n")
    if a.tif:
        import tifffile
        tifffile.imwrite(out + ".tif.part", scan)
        os.replace(out + ".tif.part", out + ".tif")
    info["seconds"]["total"] = time.perf_counter() - t0
    with open(out + ".json.part", "w") as f:
        json.dump(info, f, indent=1)
    os.replace(out + "_truth.csv.part", out + "_truth.csv")
    os.replace(out + ".json.part", out + ".json")
    os.replace(tmp, out + ".h5")   # last: the .h5 marks a complete scene (--reuse)
    print(json.dumps({k: info[k] for k in ("particles", "grains", "by_kind", "solid_fraction")}
                     | {"measured": info.get("measured"), "gap": info.get("measured_gap_vox"),
                        "seconds": info["seconds"]}))


if __name__ == "__main__":
    sys.exit(main())

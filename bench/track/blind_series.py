#!/usr/bin/python3
"""An independent ("blind") oedometer stage series with its truth lineage.

For issue 20: tomograin track is to be checked "on multi-stage scans from
another generator, with label numbers that change from stage to stage".
data_synth's series (data_synth/motion.hpp) are the tracker's development
data; this one is built on bench/segmentation/blind_scene.py (grain shapes,
pores, partial volume, imaging), which shares no code with data_synth, and
differs from data_synth's series where a real scan may:
  * the MOVING platen is at the BOTTOM (--platen bottom, default) or the
    top; the scan is a fixed window inside a taller specimen, so grains
    enter the window from the moving end as the specimen shortens (`new`)
    and leave nowhere;
  * grains are near-spheres with 3 % lobes and 8 % ellipticity, not
    data_synth's granules; fragment planes are off the centre by up to
    0.15 R, chips are caps beyond 0.6-0.85 R;
  * every stage's labels are a new random permutation;
  * per-grain rotations about random axes, up to --rotation-deg at the
    final strain, and a jitter random walk.

Kinematics, with strains e_0 = 0 < e_1 < ... < e_n (--strains): grains are
packed (blind_scene.pack) for the final, shortest specimen; at stage s a
grain centre's distance from the fixed platen is scaled by
(1 - e_s)/(1 - e_n) (uniform axial strain), plus a jitter random walk
(per axis, RMS --jitter x R at e_n) and a rotation about the grain's centre
(angle --rotation-deg x e_s/e_n about an axis drawn once per grain).
Breakage (decided once per grain, so pores can be kept clear of every
plane): grain g breaks at the first stage with u_g < broken_s (--broken),
as a split (2 halves, one plane through c + U(-0.15, 0.15) R n), a
fragmentation (3 or 4 pieces: a split whose halves are both, or one,
split again at once by a second plane) or a chipping (cap beyond
U(0.6, 0.85) R, kept as a chip), in the proportions --modes. A half or
a chipped body that is still whole splits again at each later stage with
probability --rebreak (a plane containing its first plane's normal); chips
never do. Each piece drifts away from its fracture planes by --drift x R x
(e_s - e_b)/e_n after breaking at stage b. The gap (--gap voxels) is
centred on each plane.

Truth events (tomograin track's vocabulary): intact (continuation and stage
0), split (both pieces), fragmentation (every piece), chipping (the body),
chip (the chip); a particle whose parent has no voxels in the previous
stage's window is `new` with grain 0; grain = the stage-0 label of the
grain (0 if the grain was not in the window at stage 0).

Outputs
  PREFIX_stage{s}.h5  /scan (uint16), /labels (uint32 truth, permuted per
                      stage); voxel_size_m attribute (1e-5, nominal)
  PREFIX_lineage.csv  stage,label,parent_label,grain,event,volume_vox,
                      border (1: touches a face of the volume), face_vox
                      (its voxels on the faces: the truth side of track's
                      % broken leaves out the grains they cut, as track's
                      own does), cz_vox,cy_vox,cx_vox, rz_deg,ry_deg,rx_deg
                      (the turn since the previous stage, a rotation
                      vector in degrees) (track's columns)
  PREFIX.json         parameters, counts per stage and event

usage: blind_series.py -o PREFIX [--size 192] [--radius 16] [--seed 1] ...
"""
import argparse
import csv
import json
import math
import os
import sys
import time

import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "segmentation"))
import blind_scene as bs  # noqa: E402


def rotation(axis, deg):
    a = math.radians(deg)
    x, y, z = axis
    c, s, C = math.cos(a), math.sin(a), 1 - math.cos(a)
    return np.array([[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                     [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                     [z * x * C - y * s, z * y * C + x * s, c + z * z * C]], np.float32)


class Piece(bs.Particle):
    """A blind_scene particle turned by Rm about its grain's centre: the
    signed distance is evaluated in the grain's own frame (v Rm = Rm^T v)."""

    def __init__(self, grain, kind, cuts, shift, Rm):
        super().__init__(grain, kind, cuts, shift)
        self.Rm = Rm

    def d_filled(self, v):
        return super().d_filled(v @ self.Rm)

    def d_solid(self, v, d):
        return super().d_solid(v @ self.Rm, d)


def plan_grain(rng, a, r0, nstages, u):
    """The grain's breakage history: a list of pieces, each a dict with
    cuts (n, off, side) in the grain frame, born (stage the piece appears),
    dies (stage it is replaced by its children, or None), event at birth,
    parent piece index (None: the grain itself), and the planes for pores."""
    brk = next((s for s in range(1, nstages) if u < a.broken[s]), None)
    grain = {"cuts": [], "born": 0, "dies": brk, "event": "intact", "parent": None, "kind": "intact"}
    pieces = [grain]
    planes = []
    if brk is None:
        return pieces, planes
    mode = rng.choice(["split", "fragmentation", "chipping"], p=a.modes)

    def add(parent, cuts, born, event, kind):
        pieces.append({"cuts": cuts, "born": born, "dies": None, "event": event, "parent": parent, "kind": kind})
        return len(pieces) - 1

    n1 = bs.random_unit(rng)
    if mode == "chipping":
        off = rng.uniform(0.6, 0.85) * r0
        planes.append((n1, off))
        body = add(0, [(n1, off, -1.0)], brk, "chipping", "body")
        add(0, [(n1, off, 1.0)], brk, "chip", "chip")
        halves = [body]
    else:
        off = rng.uniform(-0.15, 0.15) * r0
        planes.append((n1, off))
        if mode == "split":
            halves = [add(0, [(n1, off, s)], brk, "split", "half") for s in (1.0, -1.0)]
        else:
            # a second plane containing n1's perpendicular direction: pieces are wedges
            t = bs.random_unit(rng)
            n2 = t - (t @ n1) * n1
            n2 /= np.linalg.norm(n2)
            off2 = rng.uniform(-0.1, 0.1) * r0
            planes.append((n2, off2))
            halves = []
            four = rng.uniform() < 0.5
            for s1 in (1.0, -1.0):
                if four or s1 > 0:
                    for s2 in (1.0, -1.0):
                        add(0, [(n1, off, s1), (n2, off2, s2)], brk, "fragmentation", "wedge")
                else:
                    halves.append(add(0, [(n1, off, s1)], brk, "fragmentation", "half"))
    # second breakage of halves and chipped bodies, one plane containing n1
    for h in list(halves):
        for s in range(brk + 1, nstages):
            if rng.uniform() < a.rebreak:
                t = bs.random_unit(rng)
                n3 = t - (t @ n1) * n1
                n3 /= np.linalg.norm(n3)
                off3 = rng.uniform(-0.1, 0.1) * r0
                planes.append((n3, off3))
                pieces[h]["dies"] = s
                for s3 in (1.0, -1.0):
                    add(h, pieces[h]["cuts"] + [(n3, off3, s3)], s, "split", "quarter")
                break
    return pieces, planes


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", required=True, help="output prefix")
    ap.add_argument("--size", type=bs.parse_size, default=(192, 192, 192), help="scan window, voxels: N or nz,ny,nx (192)")
    ap.add_argument("--radius", type=float, default=16.0, help="mean grain radius, voxels (16)")
    ap.add_argument("--spread", type=float, default=0.12, help="relative standard deviation of the radii (0.12)")
    ap.add_argument("--radius-range", type=bs.parse_range, default=(0.6, 1.5),
                    help="radii clipped to [LO R, HI R] (0.6,1.5; with a larger --spread: a wide grading)")
    ap.add_argument("--phi", type=float, default=0.58, help="solid fraction of the final packing (0.58)")
    ap.add_argument("--strains", default="0,0.044,0.0712,0.1128,0.1548", help="axial strain per stage (the study's)")
    ap.add_argument("--broken", default="0,0.2,0.4,0.55,0.7", help="fraction of grains broken by each stage (nested)")
    ap.add_argument("--modes", default="0.6,0.2,0.2", help="split, fragmentation, chipping shares of primary breaks")
    ap.add_argument("--rebreak", type=float, default=0.2, help="per-stage probability that a half or body splits again")
    ap.add_argument("--platen", choices=("bottom", "top"), default="bottom", help="the moving platen's end (bottom)")
    ap.add_argument("--jitter", type=float, default=0.05, help="RMS jitter per axis at the final strain, x R (0.05)")
    ap.add_argument("--rotation-deg", type=float, default=8.0, help="rotation at the final strain, degrees (8)")
    ap.add_argument("--drift", type=float, default=0.06, help="fragments' drift per unit e/e_n, x R (0.06)")
    ap.add_argument("--gap", type=float, default=1.0, help="fragment gap, voxels (1)")
    ap.add_argument("--pores", type=bs.parse_range, default=(1.0, 3.0), help="pore radius range, voxels (1,3)")
    ap.add_argument("--psf", type=float, default=0.7, help="Gaussian PSF sigma, voxels (0.7)")
    ap.add_argument("--cnr", type=float, default=13.0, help="contrast-to-noise ratio (13)")
    ap.add_argument("--grain-contrast", type=bs.parse_range, default=(1.0, 1.0),
                    help="LO,HI: each grain's contrast over the void, U(LO,HI) of the solid's, kept by its fragments "
                         "at every stage (blind_scene.py's; default 1,1: all alike)")
    ap.add_argument("--supersample", type=int, default=3, help="samples per axis near surfaces (3)")
    ap.add_argument("--seed", type=int, default=1, help="random seed (1)")
    a = ap.parse_args(argv)
    a.strains = [float(v) for v in a.strains.split(",")]
    a.broken = [float(v) for v in a.broken.split(",")]
    a.modes = np.array([float(v) for v in a.modes.split(",")])
    a.modes /= a.modes.sum()
    n = len(a.strains)
    if len(a.broken) != n or a.strains[0] != 0 or any(b <= c for c, b in zip(a.strains, a.strains[1:])):
        ap.error("--strains must start at 0 and increase; --broken needs one value per stage")
    import h5py
    t0 = time.perf_counter()
    rng = np.random.default_rng(a.seed)
    shape = a.size
    emax = a.strains[-1]
    nz = shape[0]
    # the packing of the final, shortest specimen over the window: at earlier
    # stages the distances from the fixed platen are longer, so the window
    # shows less of it and the rest enters from the moving end
    centres, shapes, u, _ = bs.pack(rng, shape, a.radius, a.spread, a.phi, 0.0, 0.0, radius_range=a.radius_range)
    z_fixed = float(nz) if a.platen == "bottom" else 0.0
    grains = []
    for k in range(centres.shape[0]):
        g = bs.make_grain(k + 1, centres[k], shapes, k)
        pieces, planes = plan_grain(rng, a, shapes["r0"][k], n, u[k])
        g["pores_list"] = bs.place_pores(rng, g, [(nn, off, a.gap / 2 + 1) for nn, off in planes], a)
        axis = bs.random_unit(rng)
        walk = np.cumsum([np.zeros(3)] + [rng.normal(size=3) * math.sqrt((a.strains[s] - a.strains[s - 1]) / emax)
                                          for s in range(1, n)], axis=0) * a.jitter * a.radius
        grains.append({"g": g, "pieces": pieces, "axis": axis, "walk": walk})
    grain_contrast = bs.draw_grain_contrast([G["g"]["id"] for G in grains], a.grain_contrast, a.seed)

    lineage = []
    G_axis = [np.asarray(G["axis"], float) for G in grains]
    prev_label = {}   # (grain index, piece index) -> label at the previous stage
    prev_grain = {}   # label at the previous stage -> its grain
    counts = []
    for s in range(n):
        scale = (1 - a.strains[s]) / (1 - emax)
        parts, keys = [], []
        for gi, G in enumerate(grains):
            g0 = G["g"]
            c = g0["c"].copy()
            c[0] = z_fixed + (c[0] - z_fixed) * scale
            c = c + G["walk"][s]
            Rm = rotation(G["axis"], a.rotation_deg * a.strains[s] / emax)
            g = dict(g0, c=c)
            for pi, p in enumerate(G["pieces"]):
                if p["born"] > s or (p["dies"] is not None and p["dies"] <= s):
                    continue
                if p["born"] == 0 and pi == 0:
                    shift = np.zeros(3)
                else:
                    # away from its fracture planes (the sum of its sides' normals), turned with the grain,
                    # from the stage its first ancestor piece broke off
                    away = sum(side * nn for nn, _, side in p["cuts"])
                    away = away / max(np.linalg.norm(away), 1e-9)
                    first = p
                    while first["parent"] not in (None, 0):
                        first = G["pieces"][first["parent"]]
                    b = first["born"]
                    shift = (Rm @ away) * a.drift * a.radius * (a.strains[s] - a.strains[b - 1]) / emax
                cuts = [(nn, off, side, a.gap / 2) for nn, off, side in p["cuts"]]
                piece = Piece(g, p["kind"], cuts, shift, Rm)
                piece.pores = [(pc, pr) for pc, pr in g0["pores_list"]
                               if all(side * (pc @ nn - off) > 0 for nn, off, side in p["cuts"])]
                parts.append(piece)
                keys.append((gi, pi))
        solid, truth, _, dens = bs.render(parts, shape, a.supersample, grain_contrast)
        present = np.bincount(truth.ravel(), minlength=len(parts) + 1)
        perm = rng.permutation(int((present[1:] > 0).sum())) + 1
        lut = np.zeros(len(parts) + 1, np.uint32)
        j = 0
        for lab in range(1, len(parts) + 1):
            if present[lab] > 0:
                lut[lab] = perm[j]
                j += 1
        truth = lut[truth]
        com = ndimage.center_of_mass(truth > 0, truth, np.arange(1, j + 1)) if j else []
        vol = np.bincount(truth.ravel(), minlength=j + 1)
        border = set()
        face_vox = np.zeros(j + 1, np.int64)  # one per face an edge voxel lies on, as tomograin track counts
        for face in (truth[0], truth[-1], truth[:, 0], truth[:, -1], truth[:, :, 0], truth[:, :, -1]):
            border.update(np.unique(face).tolist())
            face_vox += np.bincount(face.ravel(), minlength=j + 1)
        labels_now = {}
        grain_now = {}
        ev_count = {}
        for lab, key in enumerate(keys, 1):
            L = int(lut[lab])
            if L == 0:
                continue
            labels_now[key] = L
            gi, pi = key
            p = grains[gi]["pieces"][pi]
            if s == 0:
                parent, event, grain = 0, "intact", L
            else:
                pk = (gi, pi) if p["born"] < s else (gi, p["parent"])
                parent = prev_label.get(pk, 0)
                event = p["event"] if p["born"] == s else "intact"
                grain = prev_grain.get(parent, 0)
                if parent == 0:
                    event, grain = "new", 0
            grain_now[L] = grain
            cz, cy, cx = com[L - 1]
            # the turn since the previous stage (its grain's, about the grain's fixed axis): a rotation
            # vector in degrees, (z, y, x) array axes as tomograin track writes it
            turn = G_axis[gi] * (a.rotation_deg * (a.strains[s] - a.strains[s - 1]) / emax if s else 0.0)
            lineage.append((s, L, parent, grain, event, int(vol[L]), int(L in border), int(face_vox[L]), cz + 0.5, cy + 0.5,
                            cx + 0.5, turn[0], turn[1], turn[2]))
            ev_count[event] = ev_count.get(event, 0) + 1
        prev_label, prev_grain = labels_now, grain_now
        # imaging (blind_scene's)
        contrast = bs.SOLID - bs.VOID
        seen = solid if dens is None else dens  # each grain's own attenuation
        img = ndimage.gaussian_filter(seen, a.psf, mode="nearest") if a.psf > 0 else seen
        img = img * contrast + bs.VOID
        if a.cnr > 0:
            img += (contrast / a.cnr) * rng.normal(0, 1, size=shape).astype(np.float32)
        scan = np.clip(np.rint(img), 0, 65535).astype(np.uint16)
        with h5py.File(f"{a.output}_stage{s}.h5", "w") as f:
            for name, data in (("scan", scan), ("labels", truth)):
                d = f.create_dataset(name, data=data, compression="gzip", compression_opts=1)
                d.attrs["voxel_size_m"] = np.array([1e-5, 1e-5, 1e-5])
            f.attrs["voxel_size_m"] = np.array([1e-5, 1e-5, 1e-5])
            f.attrs["strain"] = a.strains[s]
        counts.append({"stage": s, "particles": j, "events": ev_count})
        print(f"stage {s}: strain {a.strains[s]:.4f}, {j} particles, events {ev_count}", flush=True)
    with open(f"{a.output}_lineage.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["stage", "label", "parent_label", "grain", "event", "volume_vox", "border", "face_vox", "cz_vox",
                    "cy_vox", "cx_vox", "rz_deg", "ry_deg", "rx_deg"])
        for row in lineage:
            w.writerow(list(row[:8]) + [f"{v:.3f}" for v in row[8:]])
    info = {"generator": "bench/track/blind_series.py (on blind_scene.py; independent of data_synth)",
            "params": {k: (v.tolist() if isinstance(v, np.ndarray) else list(v) if isinstance(v, tuple) else v)
                       for k, v in vars(a).items()},
            "stages": counts, "seconds": time.perf_counter() - t0}
    with open(f"{a.output}.json", "w") as f:
        json.dump(info, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())

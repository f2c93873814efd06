#!/usr/bin/python3
"""Truth labels of a voxelised DEM snapshot (`tomograin voxelise ... --truth-table`)
against the segmented labels of its grey scan (`tomograin segment`), particles
of d_eq >= 0.2 mm (the detection limit of measure/label_stats.hpp):

  kept    a truth particle one segmented label covers by more than half of
          its voxels, that label being more than half its own (mutual majority)
  merged  its majority label is mostly another particle's
  lost    the rest (no label holds half of it: split into pieces or missed)
  split   truth particles that host two or more segmented labels (each label
          assigned to the truth particle holding most of its voxels)

A count ratio (segmented / truth above the limit) hides merges behind splits;
`kept` does not. Usage: match.py TRUTH.h5 SEGMENTED.h5"""
import sys

import h5py
import numpy as np

LIMIT_MM = 0.2

with h5py.File(sys.argv[1]) as f:
    t = f["/labels"][...].ravel().astype(np.int64)
    vox = float(np.ravel(f["/volume"].attrs["voxel_size_m"])[0])
with h5py.File(sys.argv[2]) as f:
    s = f["/labels"][...].ravel().astype(np.int64)
if t.shape != s.shape:
    sys.exit(f"match.py: {sys.argv[1]} and {sys.argv[2]} differ in shape")


def d_eq_mm(voxels):
    return (6 * voxels * vox**3 / np.pi) ** (1 / 3) * 1e3


tsize = np.bincount(t)
ssize = np.bincount(s)
both = (t > 0) & (s > 0)
ns = len(ssize)
pairs, overlap = np.unique(t[both] * ns + s[both], return_counts=True)
pt, ps = pairs // ns, pairs % ns
order = np.argsort(overlap, kind="stable")  # ascending: the largest overlap is written last and wins
best, best_n = np.zeros(len(tsize), np.int64), np.zeros(len(tsize), np.int64)
best[pt[order]], best_n[pt[order]] = ps[order], overlap[order]
host = np.zeros(ns, np.int64)
host[ps[order]] = pt[order]

truth = np.nonzero(d_eq_mm(tsize) >= LIMIT_MM)[0]
truth = truth[truth > 0]
seg = np.nonzero(d_eq_mm(ssize) >= LIMIT_MM)[0]
seg = seg[seg > 0]
holds_half = best_n[truth] * 2 > tsize[truth]
mutual = best_n[truth] * 2 > ssize[best[truth]]
kept = int(np.sum(holds_half & mutual))
merged = int(np.sum(holds_half & ~mutual))
pieces = np.bincount(host[seg], minlength=len(tsize))
pieces[0] = 0
split = np.nonzero(pieces >= 2)[0]
print(f"voxel {vox * 1e6:.1f} um: truth above the limit {len(truth)}, segmented {len(seg)} "
      f"(ratio {len(seg) / len(truth):.3f}); kept one to one {kept} ({kept / len(truth):.3f}), merged {merged}, "
      f"lost {len(truth) - kept - merged}; {len(split)} truth particles split into {int(pieces[split].sum())} "
      f"labels (d_eq 0.5-1 mm: {int(np.sum((d_eq_mm(tsize[split]) >= 0.5) & (d_eq_mm(tsize[split]) < 1)))})")

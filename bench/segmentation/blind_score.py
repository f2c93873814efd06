#!/usr/bin/python3
"""Score a labelling against a blind_scene.py truth (issue 19's definitions).

  * matched: a truth particle and a label with IoU >= 0.5 (one-to-one: two
    regions with IoU > 0.5 with the same region cannot exist);
    F1 = 2 matched / (n_true + n_pred)
  * halves recovered: split halves (kind half) that are matched, over all
    halves (each half counts on its own)
  * over-segmented: truth particles split over >= 2 labels each holding
    >= 20 % of the particle
  * under-segmenting: labels holding >= 2 truth particles, each >= 20 % of
    that particle inside the label; under_one_grain: those of them whose
    pieces all come from one grain (halves or a chip glued back)
  * median |dV/V| over matched particles (V: truth voxels), of the label's
    voxel count; with a particle table (`tomograin measure --grey`, its
    volume_mm3 over the voxel volume) also of the volume tomograin reports:
    median_abs_dv_reported, on the same matched pairs
  * pore over-segmentation: INTACT grains (every one has 2-5 pores) that are
    over-segmented, the count
  * shells (blind_scene.py --shell-frac, walls 2-4 voxels thick): how many
    are matched (shells_recovered), and the share of their truth voxels
    left unlabelled (shell_unlabelled: the threshold's partial-volume skin,
    watershed lines, gaps between pieces)
Differences from accuracy.py (data_synth truth): 20 % instead of 10 % for
the over/under pieces, and halves counted one by one instead of pairs.

usage: blind_score.py PREFIX (.h5 truth) LABELS(.h5 | _labels.raw) [--particles CSV] [--json OUT]
"""
import argparse
import csv
import json
import sys

import os

import numpy as np
import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import accuracy  # noqa: E402  (print_result: one way to report scores)

PIECE = 0.2


def load_truth(prefix):
    with h5py.File(prefix + ".h5", "r") as f:
        truth = f["labels"][...]
    with open(prefix + "_truth.csv") as f:
        table = list(csv.DictReader(f))
    return truth, table


def load_labels(path, shape):
    if path.endswith(".raw"):
        return np.fromfile(path, dtype="<u4").reshape(shape)
    name = "labels"
    if ":" in path:
        path, name = path.split(":", 1)
    with h5py.File(path, "r") as f:
        return f[name][...]


def label_voxel_m3(labels_h5):
    """Voxel volume (m^3) of a tomograin label file (its voxel_size_m)."""
    path, name = labels_h5.split(":", 1) if ":" in labels_h5 else (labels_h5, "labels")
    with h5py.File(path, "r") as f:
        h = f[name].attrs.get("voxel_size_m", f.attrs.get("voxel_size_m"))
    return float(np.prod(h))


def load_reported_volumes(csv_path, voxel_m3):
    """label -> reported volume in voxels, from a tomograin particle table."""
    with open(csv_path) as f:
        return {int(r["label"]): float(r["volume_mm3"]) * 1e-9 / voxel_m3 for r in csv.DictReader(f)}


def evaluate(truth, pred, table, reported=None):
    t = truth.ravel().astype(np.int64)
    p = pred.ravel().astype(np.int64)
    st = np.bincount(t)
    sp = np.bincount(p)
    both = (t > 0) & (p > 0)
    key = t[both] * (int(sp.size) + 1) + p[both]
    k, c = np.unique(key, return_counts=True)
    kt, kp = k // (sp.size + 1), k % (sp.size + 1)
    iou = c / (st[kt] + sp[kp] - c)
    m = iou >= 0.5
    match = dict(zip(kt[m].tolist(), kp[m].tolist()))
    vol_err = np.abs(sp[kp[m]] - st[kt[m]]) / st[kt[m]]
    rep_err = None
    if reported is not None:
        rep = np.array([reported[int(q)] for q in kp[m]], dtype=float)
        rep_err = np.abs(rep - st[kt[m]]) / st[kt[m]]
    big = c >= PIECE * st[kt]
    pieces_t = np.bincount(kt[big], minlength=st.size)
    pieces_p = np.bincount(kp[big], minlength=sp.size)
    n_true = int((st[1:] > 0).sum())
    n_pred = int((sp[1:] > 0).sum())
    kinds = {int(r["label"]): r["kind"] for r in table}
    parent = np.zeros(st.size, np.int64)
    for r in table:
        if int(r["label"]) < st.size:
            parent[int(r["label"])] = int(r["parent"])
    # under-segmenting labels whose pieces all come from one grain (halves, chip glued back)
    ub = kp[big]
    under = np.flatnonzero(pieces_p >= 2)
    pmin = np.full(sp.size, np.iinfo(np.int64).max)
    pmax = np.full(sp.size, -1)
    np.minimum.at(pmin, ub, parent[kt[big]])
    np.maximum.at(pmax, ub, parent[kt[big]])
    same = int(np.sum(pmin[under] == pmax[under]))
    halves = [lab for lab, kd in kinds.items() if kd == "half" and lab < st.size and st[lab] > 0]
    intact = [lab for lab, kd in kinds.items() if kd == "intact" and lab < st.size and st[lab] > 0]
    shells = [lab for lab, kd in kinds.items() if kd == "shell" and lab < st.size and st[lab] > 0]
    shell_vox = int(st[shells].sum()) if shells else 0
    shell_labelled = int(np.isin(t[both], shells).sum()) if shells else 0
    tp = len(match)
    return {"n_true": n_true, "n_pred": n_pred, "matched": tp,
            "f1": 2 * tp / (n_true + n_pred) if n_true + n_pred else 1.0,
            "halves": len(halves), "halves_recovered": sum(1 for h in halves if h in match),
            "over_segmented": int((pieces_t[1:] >= 2).sum()),
            "under_segmenting": int((pieces_p[1:] >= 2).sum()),
            "under_one_grain": same,
            "median_abs_dv": float(np.median(vol_err)) if tp else None,
            "median_abs_dv_reported": float(np.median(rep_err)) if tp and rep_err is not None else None,
            "intact": len(intact),
            "pore_over_segmented_intact": sum(1 for i in intact if pieces_t[i] >= 2),
            "shells": len(shells), "shells_recovered": sum(1 for h in shells if h in match),
            "shell_unlabelled": 1 - shell_labelled / shell_vox if shell_vox else None}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("prefix", help="blind_scene.py output prefix")
    ap.add_argument("labels", help="labels: .h5[:dataset] (default /labels) or a raw little-endian uint32 file (.raw)")
    ap.add_argument("--particles", help="tomograin particle table (measure --grey) of LABELS: also score its volumes")
    ap.add_argument("--json")
    a = ap.parse_args()
    truth, table = load_truth(a.prefix)
    reported = None
    if a.particles:
        reported = load_reported_volumes(a.particles, label_voxel_m3(a.labels))
    accuracy.print_result(evaluate(truth, load_labels(a.labels, truth.shape), table, reported), a.json)


if __name__ == "__main__":
    sys.exit(main())

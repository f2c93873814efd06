#!/usr/bin/python3
"""Accuracy of a labelling against data_synth truth (same rules as
segmentation/accuracy.hpp: a true particle is detected by a label with
IoU >= 0.5; F1 = 2 TP / (n_true + n_pred); over-segmented: >= 2 labels each
hold >= 10 % of it; split halves: both halves of a parent detected by two
distinct labels, counted over pairs with both halves uncropped).

usage: accuracy.py SCAN.h5 LABELS(.h5 | _labels.raw) [--json OUT]
"""
import argparse, csv, json, sys
import numpy as np
import h5py


def load_labels(path, shape):
    if path.endswith(".raw"):
        return np.fromfile(path, dtype="<u4").reshape(shape)
    with h5py.File(path, "r") as f:
        return f["labels"][...]


def evaluate(truth, pred, table, min_voxels=1):
    t = truth.ravel().astype(np.uint64)
    p = pred.ravel().astype(np.uint64)
    st = np.bincount(t.astype(np.int64))
    sp = np.bincount(p.astype(np.int64))
    # particles and labels below min_voxels are not counted (as AccuracyOptions)
    st[st < min_voxels] = 0
    sp[sp < min_voxels] = 0
    both = (t > 0) & (p > 0)
    key = (t[both] << np.uint64(32)) | p[both]
    k, c = np.unique(key, return_counts=True)
    kt = (k >> np.uint64(32)).astype(np.int64)
    kp = (k & np.uint64(0xffffffff)).astype(np.int64)
    keep = (st[kt] > 0) & (sp[kp] > 0)
    k, c, kt, kp = k[keep], c[keep], kt[keep], kp[keep]
    iou = c / (st[kt] + sp[kp] - c)
    match = {}
    for a, b, v in zip(kt, kp, iou):
        if v >= 0.5:
            match[int(a)] = int(b)
    big = c >= 0.1 * st[kt]
    pieces_t = np.bincount(kt[big], minlength=st.size)
    pieces_p = np.bincount(kp[big], minlength=sp.size)
    n_true = int((st[1:] > 0).sum())
    n_pred = int((sp[1:] > 0).sum())
    tp = len(match)
    verr = [(sp[b] - st[a]) / st[a] for a, b in match.items()]
    res = {"n_true": n_true, "n_pred": n_pred, "matched": tp,
           "f1": 2 * tp / (n_true + n_pred) if n_true + n_pred else 1.0,
           "over_segmented": int((pieces_t[1:] >= 2).sum()),
           "under_segmenting": int((pieces_p[1:] >= 2).sum()),
           "median_volume_error": float(np.median(verr)) if verr else 0.0}
    # split halves
    halves = {}
    for row in table:
        if row["kind"] == "half":
            halves.setdefault(int(float(row["parent"])), []).append(row)
    pairs = rec = 0
    for parent, rows in halves.items():
        if len(rows) != 2 or any(int(float(r["cropped"])) for r in rows):
            continue
        ids = [int(float(r["id"])) for r in rows]
        if any(i >= st.size or st[i] == 0 for i in ids):
            continue
        pairs += 1
        m = [match.get(i) for i in ids]
        rec += m[0] is not None and m[1] is not None and m[0] != m[1]
    res["split_pairs"] = pairs
    res["split_recovered"] = rec
    res["split_fraction"] = rec / pairs if pairs else None
    # intact grains: over-segmentation caused by pores
    intact = [int(float(r["id"])) for r in table if r["kind"] == "grain" and int(float(r["pores"])) > 0]
    res["porous_grains"] = sum(1 for i in intact if i < st.size and st[i] > 0)
    res["porous_grains_over_segmented"] = sum(1 for i in intact if i < st.size and st[i] > 0 and pieces_t[i] >= 2)
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scan")
    ap.add_argument("labels")
    ap.add_argument("--json")
    ap.add_argument("--min-voxels", type=int, default=1, help="leave out smaller particles and labels")
    a = ap.parse_args()
    with h5py.File(a.scan, "r") as f:
        truth = f["labels"][...]
    pred = load_labels(a.labels, truth.shape)
    with open(a.scan[:-3] + "_truth.csv") as f:
        table = list(csv.DictReader(f))
    print_result(evaluate(truth, pred, table, a.min_voxels), a.json)


def print_result(res, json_path=None):
    """The scores on stdout (one JSON line) and, when asked, in a file."""
    print(json.dumps(res))
    if json_path:
        with open(json_path, "w") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())

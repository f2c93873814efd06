#!/usr/bin/python3
"""tomograin track on a stage series from another generator (issue 20).

bench/track/blind_series.py (built on bench/segmentation/blind_scene.py, no
code shared with data_synth) renders a 5-stage oedometer series of a scan
WINDOW inside a taller specimen, the moving platen below the window (grains
enter the field through the bottom face as the specimen shortens), labels
permuted at every stage, grains rotating up to 8 degrees. The tracker runs
on the truth label volumes (the tracker alone) and is scored here against
the truth lineage, labels being the truth's:
  * right parent >= 0.98 of the particles at stages >= 1 (before grains
    entering the field kept their parent: 0.969 on the dev seed), >= 0.995
    (issue 20's figure for the tracker alone) of those clear of the faces;
  * breakage events (split, fragmentation, chipping) of parents clear of
    the faces, keyed by (stage, parent label, type): recall and precision
    >= 0.95 (the faces hide part of a cut parent: its events are not asked);
  * tracked `new` particles at most the truth's + 25 % + 3.
Seed 1 was used while building the generator and the entering rule; this
test's seed 11 was run once on the final code. 112^3, R 10 voxels: ~25 s.
The truth labels are tracked with the grey scans (`--scans`): the intact
particles' turns against the generator's (each grain turns about its own
axis, ~2 degrees a stage): median error under 0.6 of the median turn, and
>= 85 % of the errors within three standard errors.
The same series segmented with the defaults (`segment --grain-radius-vox 10`)
and tracked, each label mapped to the truth particle covering most of it:
regression bounds under what the final code measured there (right parent
of the particles clear of the faces >= 0.98; interior events recall >= 0.8,
precision >= 0.85).

usage: blind_series_test.py TOMOGRAIN [WORKDIR]
"""
import collections
import csv
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "bench", "track"))
import blind_series  # noqa: E402

SEED, SIZE, R, STAGES = 11, 112, 10, 5
BREAKS = ("split", "fragmentation", "chipping")


def events(rows):
    """(stage, parent label) -> event type of its children (chipping when a
    child is the chipped body; intact when all are)."""
    kids = collections.defaultdict(set)
    for r in rows:
        if int(r["stage"]) > 0 and int(r["parent_label"]) > 0:
            kids[(int(r["stage"]), int(r["parent_label"]))].add(r["event"])
    out = {}
    for key, ev in kids.items():
        out[key] = "chipping" if "chipping" in ev else next((e for e in ("fragmentation", "split") if e in ev), "intact")
    return out


def main():
    tomograin = os.path.abspath(sys.argv[1])
    if not os.access(tomograin, os.X_OK):
        sys.exit(f"FAIL: no tomograin program at {tomograin}")
    if len(sys.argv) > 2:
        os.makedirs(sys.argv[2], exist_ok=True)
        run(tomograin, sys.argv[2])
    else:
        with tempfile.TemporaryDirectory(prefix="tg_blind_series_") as work:
            run(tomograin, work)


def correspondence(labels_h5, truth_h5):
    """Segmented label -> the truth particle covering most of its voxels (ties: the smaller)."""
    with h5py.File(labels_h5, "r") as f:
        seg = f["labels"][...].ravel().astype(np.int64)
    with h5py.File(truth_h5, "r") as f:
        tru = f["labels"][...].ravel().astype(np.int64)
    m = (seg > 0) & (tru > 0)
    base = int(tru.max()) + 1
    k, c = np.unique(seg[m] * base + tru[m], return_counts=True)
    best = {}
    for key, n in zip(k.tolist(), c.tolist()):
        ls, lt = divmod(key, base)
        if ls not in best or n > best[ls][0]:
            best[ls] = (n, lt)
    return {ls: lt for ls, (n, lt) in best.items()}


def score(truth, tracked, maps=None):
    """Right parent (all, and particles clear of the faces) and the interior breakage events'
    recall and precision; maps[s]: tracked label -> truth label (None: the truth's labels)."""
    tmap = (lambda s, l: l) if maps is None else (lambda s, l: maps[s].get(l, 0) if l else 0)  # noqa: E731
    tparent = {(int(r["stage"]), int(r["label"])): int(r["parent_label"]) for r in truth}
    border = {(int(r["stage"]), int(r["label"])): r["border"] == "1" for r in truth}
    n = right = n_in = right_in = 0
    for r in tracked:
        s = int(r["stage"])
        if s == 0:
            continue
        q = tmap(s, int(r["label"]))
        ok = tmap(s - 1, int(r["parent_label"])) == tparent.get((s, q), 0)
        n, right = n + 1, right + ok
        if not border.get((s, q), True):
            n_in, right_in = n_in + 1, right_in + ok
    interior = lambda key: not border.get((key[0] - 1, key[1]), True)  # noqa: E731
    t_ev = {(k, e) for k, e in events(truth).items() if e in BREAKS and interior(k)}
    k_ev = {((k[0], tmap(k[0] - 1, k[1])), e) for k, e in events(tracked).items() if e in BREAKS}
    k_ev = {x for x in k_ev if interior(x[0])}
    hit = len(t_ev & k_ev)
    return {"particles": n, "right": right / max(1, n), "interior": n_in, "right_in": right_in / max(1, n_in),
            "events": len(t_ev), "by_type": dict(collections.Counter(e for _, e in t_ev)),
            "recall": hit / max(1, len(t_ev)), "precision": hit / max(1, len(k_ev)),
            "new": sum(r["event"] == "new" for r in tracked)}


def rotations(truth, tracked):
    """Tracked turns (--scans) of the intact particles clear of the faces against the truth's:
    (how many fitted, median error, median truth turn, share within 3 standard errors)."""
    t = {(r["stage"], r["label"]): r for r in truth}
    err, turn, within = [], [], 0
    for r in tracked:
        q = t.get((r["stage"], r["label"]))
        if r["stage"] == "0" or r["event"] != "intact" or not q or q["event"] != "intact" or q["border"] == "1":
            continue
        w = np.array([float(q[k]) for k in ("rz_deg", "ry_deg", "rx_deg")])
        e = np.array([float(r[k]) for k in ("rz_deg", "ry_deg", "rx_deg")])
        if not np.all(np.isfinite(e)):
            continue
        err.append(np.linalg.norm(e - w))
        turn.append(np.linalg.norm(w))
        within += err[-1] <= 3 * float(r["rotation_se_deg"])
    n = len(err)
    return n, float(np.median(err)) if n else float("nan"), float(np.median(turn)) if n else 0.0, within / max(1, n)


def track(tomograin, stages, out, scans=()):
    p = subprocess.run([tomograin, "track"] + stages + ["-o", out] + (["--scans"] + list(scans) if scans else []),
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode:
        sys.exit(f"FAIL: tomograin track exit {p.returncode}\n{p.stdout}")
    return list(csv.DictReader(open(os.path.join(out, "lineage.csv"))))


def run(tomograin, work):
    prefix = os.path.join(work, f"series_{SEED}")
    blind_series.main(["-o", prefix, "--size", str(SIZE), "--radius", str(R), "--seed", str(SEED), "--platen", "bottom"])
    truth = list(csv.DictReader(open(prefix + "_lineage.csv")))
    stages = [f"{prefix}_stage{s}.h5" for s in range(STAGES)]
    tracked = track(tomograin, stages, os.path.join(work, "tracked"), [f"{x}:/scan" for x in stages])
    a = score(truth, tracked)
    rot = rotations(truth, tracked)
    segs = []
    for s in range(STAGES):
        seg = f"{prefix}_seg{s}.h5"
        p = subprocess.run([tomograin, "segment", stages[s] + ":/scan", "-o", seg, "--grain-radius-vox", str(R)],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if p.returncode:
            sys.exit(f"FAIL: tomograin segment exit {p.returncode}\n{p.stdout}")
        segs.append(seg)
    maps = [correspondence(segs[s], stages[s]) for s in range(STAGES)]
    b = score(truth, track(tomograin, segs, os.path.join(work, "tracked_seg")), maps)
    new_t = sum(r["event"] == "new" for r in truth)
    for name, x in (("truth labels", a), ("segmented", b)):
        print(f"seed {SEED}, {SIZE}^3, R {R}, {name}: {x['particles']} particles at stages >= 1, right parent "
              f"{x['right']:.4f} ({x['right_in']:.4f} of the {x['interior']} clear of the faces); interior breakage "
              f"events {x['events']} ({x['by_type']}): recall {x['recall']:.3f}, precision {x['precision']:.3f}; "
              f"new {x['new']} (truth {new_t})")
    print(f"rotations (--scans, truth labels): {rot[0]} intact particles clear of the faces fitted, median error "
          f"{rot[1]:.2f} deg on turns of {rot[2]:.2f}, {rot[3]:.3f} within 3 standard errors")
    fails = []
    # Rotation: a sign or axis slip errs by about twice the turn; bounds above what seed 11 measured
    # (R 10: the grey of a small grain holds little) and the dev series' R 12 (error 0.36 of the turn).
    if rot[0] < 100 or not rot[1] < 0.6 * rot[2] or rot[3] < 0.85:
        fails.append(f"rotations: {rot[0]} fitted, median error {rot[1]:.2f} deg on turns of {rot[2]:.2f} (>= 0.6 of "
                     f"it?), {rot[3]:.3f} within 3 standard errors (< 0.85?)")
    if a["events"] < 20:
        fails.append(f"only {a['events']} interior events in the series (the test needs >= 20)")
    if a["right"] < 0.98 or a["right_in"] < 0.995:
        fails.append(f"truth labels: right parent {a['right']:.4f} (< 0.98?), clear of the faces {a['right_in']:.4f} "
                     "(< 0.995?)")
    if a["recall"] < 0.95 or a["precision"] < 0.95:
        fails.append(f"truth labels: interior events recall {a['recall']:.3f} / precision {a['precision']:.3f} < 0.95")
    if a["new"] > 1.25 * new_t + 3:
        fails.append(f"truth labels: {a['new']} particles tracked as new against {new_t} in the truth")
    # segmented: regression bounds under what the final code measured on this seed (0.9911; 0.917 / 0.985 from
    # track_eval's pooled split, fragmentation and chipping scores)
    if b["right_in"] < 0.98:
        fails.append(f"segmented: right parent clear of the faces {b['right_in']:.4f} < 0.98")
    if b["recall"] < 0.8 or b["precision"] < 0.85:
        fails.append(f"segmented: interior events recall {b['recall']:.3f} (< 0.8?) / precision {b['precision']:.3f} "
                     "(< 0.85?)")
    if fails:
        sys.exit("FAIL: " + "; ".join(fails))
    print("OK")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""tomograin segment vs the scikit-image/scipy reference pipeline, same scan,
same run: wall time, peak memory (bytes/voxel) and accuracy against truth.

  compare_skimage.py --tomograin build/x/apps/tomograin --size 256 --work /tmp/segbench

Makes a data_synth zeolite-stages scan (stage 4: 70 % of the grains broken
into halves, multi-fragments and chips 1.5 voxels apart; porous grains, blur,
noise) at 30 um voxels (grain radius 22.7 voxels), cropped to SIZE^3, runs

  * tomograin segment (defaults; --threads N sets OMP_NUM_THREADS)
  * /work/shared/peers/skimage/ref_pipeline.py --radius 22.7 (peak_local_max
    markers, min_distance = R/2; its Feret stage is not counted in its
    segmentation time: sum of threshold..relabel stages)

and scores both with accuracy.py (IoU >= 0.5; particles and labels below
155 voxels, the study's 0.2 mm smallest grain, left out). With --trade it
also runs tomograin over a grid of marker depths h and pore criteria.
Peak memory: ru_maxrss of each child process (GNU time is not needed).
"""
import argparse, json, os, resource, subprocess, sys, time

HERE = os.path.dirname(os.path.abspath(__file__))
REF = "/work/shared/peers/skimage/ref_pipeline.py"
sys.path.insert(0, HERE)
import accuracy  # noqa: E402


def run(cmd, env=None):
    """Runs cmd, returns (wall seconds, peak RSS bytes of that child)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - t0
    if p.returncode:
        sys.exit(f"failed: {' '.join(cmd)}\n{p.stdout}")
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    # ru_maxrss of children is the max over all waited children so far: run the
    # small jobs first, or read each job's own report (both pipelines report).
    return wall, max(peak, before) * 1024, p.stdout


def score(scan, labels, min_voxels):
    import csv, h5py
    import numpy as np
    with h5py.File(scan, "r") as f:
        truth = f["labels"][...]
    pred = accuracy.load_labels(labels, truth.shape)
    with open(scan[:-3] + "_truth.csv") as f:
        table = list(csv.DictReader(f))
    return accuracy.evaluate(truth, pred, table, min_voxels)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tomograin", required=True)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--voxel-um", type=float, default=30.0)
    ap.add_argument("--work", default="/tmp/tg_segbench")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--no-skimage", action="store_true")
    ap.add_argument("--trade", action="store_true", help="speed/accuracy table over h and pore criteria")
    ap.add_argument("--min-voxels", type=int, default=155)
    ap.add_argument("--repeat", type=int, default=1,
                    help="run tomograin's default N times and report the median time (the range is printed)")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    T = os.path.abspath(a.tomograin)
    R = 680.0 / a.voxel_um
    pre = os.path.join(a.work, f"z{a.size}")
    scan = pre + "_stage4.h5"
    if not os.path.exists(scan):
        run([T, "synth", "--preset", "zeolite-stages", "--voxel-um", str(a.voxel_um), "--size", str(a.size),
             "--seed", str(a.seed), "-o", pre + ".h5"])
    env = dict(os.environ)
    if a.threads:
        env["OMP_NUM_THREADS"] = str(a.threads)
    nvox = a.size ** 3
    rows = []

    def tomo(tag, extra, repeat=1):
        out = os.path.join(a.work, f"tg_{tag}.h5")
        runs = []
        for _ in range(repeat):
            wall, _, log = run([T, "segment", scan, "-o", out, "--grain-radius-vox", f"{R:.4f}"] + extra, env)
            summ = json.load(open(out[:-3] + ".segment.json"))
            runs.append((summ["seconds_total"], wall, summ))
        # The labels are the same every run; the times are the median run's.
        runs.sort(key=lambda r: r[0])
        seg_s, wall, summ = runs[len(runs) // 2]
        if repeat > 1:
            print(f"tomograin {tag}: {repeat} runs, segment_s {runs[0][0]:.3f} .. {runs[-1][0]:.3f} s, median {seg_s:.3f} s")
        acc = score(scan, out, a.min_voxels)
        sec = summ["seconds"]
        row = {"pipeline": f"tomograin {tag}", "wall_s": wall, "segment_s": summ["seconds_total"],
               "edt_mvox_s": nvox / sec["edt"] / 1e6 if sec.get("edt") else None,
               "watershed_mvox_s": nvox / sec["watershed"] / 1e6 if sec.get("watershed") else None,
               "markers_s": sec.get("markers"), "peak_bytes_per_voxel": summ["peak_rss_bytes_per_voxel"], **acc}
        rows.append(row)
        return row

    tomo("default", [], a.repeat)
    if a.trade:
        for h in (0.5, 0.7, 1.0, 2.0, 4.0):
            tomo(f"h{h}", ["--h", str(h)])
        for s in (0.3, 0.7):
            tomo(f"sph{s}", ["--pore-min-sphericity", str(s)])
        tomo("nopores", ["--no-pores"])
        tomo("nomerge", ["--no-merge"])
    if not a.no_skimage:
        js = pre + "_stage4_raw.json"
        if not os.path.exists(js):
            run([T, "convert", scan, "-o", js])
        ref_out = os.path.join(a.work, "ref")
        wall, _, log = run(["/usr/bin/python3", REF, js, "--out", ref_out, "--radius", f"{R:.4f}"], env)
        info = json.load(open(ref_out + "_timing.json"))
        st = {r["stage"]: r for r in info["stages"]}
        seg_s = sum(st[k]["seconds"] for k in ("threshold", "binarise", "fill_pores", "edt", "markers", "watershed", "relabel"))
        peak = max(r["peak_rss_gb"] for r in info["stages"]) * 1e9
        acc = score(scan, ref_out + "_labels.raw", a.min_voxels)
        rows.append({"pipeline": "skimage ref_pipeline", "wall_s": wall, "segment_s": seg_s,
                     "edt_mvox_s": st["edt"]["mvox_per_s"], "watershed_mvox_s": st["watershed"]["mvox_per_s"],
                     "markers_s": st["markers"]["seconds"], "peak_bytes_per_voxel": peak / nvox, **acc})
    keys = ["pipeline", "segment_s", "edt_mvox_s", "watershed_mvox_s", "peak_bytes_per_voxel", "f1", "n_true", "n_pred",
            "over_segmented", "under_segmenting", "median_volume_error", "split_recovered", "split_pairs"]
    print(f"scan {scan}: {a.size}^3, grain radius {R:.1f} voxels, threads {a.threads or 'default'}")
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(f"{r[k]:.3g}" if isinstance(r[k], float) else str(r[k]) for k in keys) + " |")
    if len(rows) >= 2 and rows[-1]["pipeline"].startswith("skimage"):
        t, s = rows[0], rows[-1]
        print(f"ratio skimage/tomograin segmentation time: {s['segment_s'] / t['segment_s']:.1f}x; "
              f"memory {s['peak_bytes_per_voxel'] / t['peak_bytes_per_voxel']:.1f}x")
    json.dump(rows, open(os.path.join(a.work, f"compare_{a.size}.json"), "w"), indent=1)


if __name__ == "__main__":
    main()

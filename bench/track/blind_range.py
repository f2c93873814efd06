#!/usr/bin/python3
"""Tracking accuracy across the segmentation's blind range (issue 20).

  bench/track/blind_range.py --build build/release --size 256 --seeds 11,12 [--factors gap,psf,cnr] [-o TABLE.md]

Each point is a 5-stage data_synth oedometer series (bench/track/run_track.sh:
zeolite-stages, motion "oedometer", the study's strains and broken fractions)
imaged with one factor moved away from the middle setting of
bench/segmentation/sweep.py: fragment gap 1 voxel, PSF sigma 0.7 voxel, CNR 13
(data_synth's contrast is 29000 grey levels, so noise sigma 2230). Levels:

  gap {0.5, 1, 1.5, 2.5} voxels   psf {0.5, 0.7, 1.0, 1.5} voxels   cnr {5, 8, 13, 30}

Every stage is segmented with `tomograin segment` defaults (the grain size
from the study's 1.36 mm and the file's voxel size: what a user knows), the
stages are tracked with `tomograin track`, and track_eval scores the lineage
against the truth lineage (segmented labels mapped to the truth by majority
overlap). The table: right parent, right grain, recall / precision of split,
fragmentation and chipping, and % of intact grains broken at the last stage
beside the truth, pooled over the seeds (event figures summed, fractions
weighted by particles).

Work files: $TMPDIR/tomograin_track_bench (reused when present).
"""
import argparse
import csv
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
CONTRAST = 29000.0  # data_synth [imaging] solid_grey - void_grey (38000 - 9000)
MIDDLE = {"gap": 1.0, "psf": 0.7, "cnr": 13.0}
LEVELS = {"gap": [0.5, 1.0, 1.5, 2.5], "psf": [0.5, 0.7, 1.0, 1.5], "cnr": [5.0, 8.0, 13.0, 30.0]}
EVENTS = ("split", "fragmentation", "chipping")


def noise_for(cnr):
    return round(CONTRAST / cnr)


def series_dir(work, size, seed, p):
    return os.path.join(work, f"n{size}_s{seed}_g{p['gap']}_p{p['psf']}_n{noise_for(p['cnr'])}")


def run_point(build, size, seed, p):
    env = dict(os.environ, PSF=str(p["psf"]), NOISE=str(noise_for(p["cnr"])), KIND="segmented")
    cmd = ["bash", os.path.join(HERE, "run_track.sh"), build, str(size), str(seed), str(p["gap"])]
    r = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode:
        sys.exit(f"failed: {' '.join(cmd)}\n{r.stdout}")


def read_eval(path):
    with open(path) as f:
        return {row["figure"]: float(row["value"]) for row in csv.DictReader(f)}


def pooled(evals):
    n = sum(e["particles"] for e in evals)
    out = {"particles": n,
           "right_parent": sum(e["right_parent"] * e["particles"] for e in evals) / n,
           "right_grain": sum(e["right_grain"] * e["particles"] for e in evals) / n}
    for ev in EVENTS:
        truth = sum(e[f"{ev}_truth"] for e in evals)
        tracked = sum(e[f"{ev}_tracked"] for e in evals)
        hit_r = sum(e[f"{ev}_recall"] * e[f"{ev}_truth"] for e in evals)
        hit_p = sum(e[f"{ev}_precision"] * e[f"{ev}_tracked"] for e in evals)
        out[ev] = (hit_r / truth if truth else float("nan"), hit_p / tracked if tracked else float("nan"))
    last = max(int(k[len("pct_intact_broken_stage"):]) for k in evals[0] if k.startswith("pct_intact_broken_stage"))
    out["broken"] = [(e[f"pct_intact_broken_stage{last}"], e[f"pct_intact_broken_truth_stage{last}"]) for e in evals]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--seeds", default="11,12")
    ap.add_argument("--factors", default="gap,psf,cnr")
    ap.add_argument("-o", "--output", help="write the markdown table here too")
    a = ap.parse_args()
    work = os.path.join(os.environ.get("TMPDIR", "/tmp"), "tomograin_track_bench")
    seeds = [int(s) for s in a.seeds.split(",")]
    points = []
    for factor in a.factors.split(","):
        for level in LEVELS[factor]:
            p = dict(MIDDLE, **{factor: level})
            if p not in [q for _, q in points]:
                points.append((factor if level != MIDDLE[factor] else "middle", p))
    lines = [f"{a.size}^3, seeds {a.seeds}; middle setting gap 1 voxel, PSF 0.7 voxel, CNR 13",
             "",
             "| point | gap | PSF | CNR | particles | right parent | right grain | split R / P | fragmentation R / P | chipping R / P | % intact broken, last stage (truth) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, p in points:
        for seed in seeds:
            d = series_dir(work, a.size, seed, p)
            if not os.path.exists(os.path.join(d, "eval_segmented.csv")):
                print(f"running {name} {p} seed {seed}", file=sys.stderr, flush=True)
                run_point(a.build, a.size, seed, p)
        r = pooled([read_eval(os.path.join(series_dir(work, a.size, s, p), "eval_segmented.csv")) for s in seeds])
        ev = " | ".join(f"{r[e][0]:.3f} / {r[e][1]:.3f}" for e in EVENTS)
        broken = ", ".join(f"{b:.2f} ({t:.2f})" for b, t in r["broken"])
        lines.append(f"| {name} | {p['gap']} | {p['psf']} | {p['cnr']:g} | {r['particles']:.0f} | {r['right_parent']:.4f} | "
                     f"{r['right_grain']:.4f} | {ev} | {broken} |")
        print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    if a.output:
        with open(a.output, "w") as f:
            f.write(text)
    print(text)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Segmentation accuracy on blind_scene.py scans, one factor at a time (issue 19).

  sweep.py --tomograin BIN [--skimage] --seeds 3 -o DIR
  sweep.py --tomograin BIN --quick -o DIR          (middle setting only)
  sweep.py --tomograin NEWBIN --reuse -o DIR       (same scenes, new binary)

Middle setting (per --sizes entry SIZE:R, default 192:20): gap 1 voxel, PSF
sigma 0.7 voxel, CNR 13, pores 1-3 voxels, split 15 %, chip 5 %, cupping 0,
drift 0. Factor levels (each varied alone around the middle):
  gap {0.5, 1, 1.5, 2.5}   psf {0.5, 0.7, 1.0, 1.5}   cnr {5, 8, 13, 30}
  pores {1-2, 2-4, 3-5}    cupping {0, 0.15, 0.3}      drift {0, 2}
  corr {0, 0.7, 1.5}: the noise's correlation length, voxels (blind_scene.py
  --noise-corr; white noise smoothed, same per-voxel sigma)
  elong {1, 1.6, 2}: every grain's long axis over its other two (blind_scene.py
  --elongation; prolate grains, same volume)
  angular {0, 0.15, 0.3}: every grain cut by 12 random facet planes at
  r0 (1 - A U(0,1)) from its centre (blind_scene.py --angularity; crushed,
  faceted sand; looser packings, as faceting removes solid)
  contrast {1-1, 0.85-1, 0.7-1}: each grain's contrast over the void drawn
  in that range of the solid's (blind_scene.py --grain-contrast; grains of
  different density)
  shells {0, 0.15, 0.3}: that share of the grains drawn as open shells, walls
  2-4 voxels thick (blind_scene.py --shell-frac; bioclasts of a carbonate
  sand: issue 19's real scan)
  texture {0, 0.1, 0.15}: a texture inside every grain, attenuation x (1 + A g),
  g correlated over 2 voxels (blind_scene.py --grain-texture; grains of
  uneven density, as a real sand's)
  spread {0.12 in 0.6-1.5 R, 0.3 in 0.4-1.8 R, 0.5 in 0.3-2 R}: the grain
  radii's relative sigma and their clip (blind_scene.py --spread,
  --radius-range; a crushed sand's wide sizes, segmented with the mean R)
  R {8, 12, 20, 40, 60} at sizes {96, 128, 192, 320, 448}^3 (>= ~40-60
  whole grains each; run once, not per --sizes entry)
Seeds are 1..--seeds (or --seed-list); these were the development seeds;
tests/segmentation/blind_middle_test.py asserts on 101 and 102.

Per scene: tomograin `segment SCENE.h5:/scan --grain-radius-vox R` (nothing
else: what a user knows) and, with --skimage, the scikit-image peer
(/work/shared/peers/skimage/ref_pipeline.py SCENE.tif --radius R). Both are
scored by blind_score.py (F1 at IoU >= 0.5, halves recovered, over / under
segmented at 20 %, median |dV/V|, over-segmented intact porous grains).
Then `tomograin measure LABELS --grey SCENE.h5:/scan` (what `analyse` runs):
its volume_mm3 is scored too (median_abs_dv_reported, beside the label
counts' median_abs_dv). Time: tomograin's own seconds_total; the peer's threshold..relabel stages
(as compare_skimage.py); wall and CPU seconds of the whole command (GNU time)
in the CSV. Peak memory: the command's maximum RSS (GNU time) per voxel;
each pipeline's own report (tomograin's peak_rss_bytes_per_voxel, the
peer's largest stage peak) is kept as own_peak_b_per_vox.

Writes DIR/sweep.csv (one row per scene and pipeline), DIR/sweep.md (mean
over seeds per factor level, both pipelines side by side, and the
generator's own checks of each scene) and keeps the scenes in DIR/scenes
(--reuse skips generating a scene whose .h5 exists; segmentations are
always rerun). A new binary on the same scenes without overwriting the
first table:
  sweep.py --tomograin NEW --reuse --tag _new -o DIR   (DIR/sweep_new.md)
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blind_score  # noqa: E402

REF = "/work/shared/peers/skimage/ref_pipeline.py"
PY = "/usr/bin/python3"
TMP = "/tmp"
MIDDLE = {"gap": 1.0, "psf": 0.7, "cnr": 13.0, "pores": "1,3", "cupping": 0.0, "drift": 0.0, "corr": 0.0, "elong": 1.0,
          "angular": 0.0, "contrast": "1,1", "shells": 0.0,
          "texture": 0.0, "spread": "0.12,0.6,1.5"}
FACTORS = {"gap": [0.5, 1.0, 1.5, 2.5], "psf": [0.5, 0.7, 1.0, 1.5], "cnr": [5.0, 8.0, 13.0, 30.0],
           "pores": ["1,2", "2,4", "3,5"], "cupping": [0.0, 0.15, 0.3], "drift": [0.0, 2.0],
           "corr": [0.0, 0.7, 1.5], "elong": [1.0, 1.6, 2.0],
           "angular": [0.0, 0.15, 0.3], "contrast": ["1,1", "0.85,1", "0.7,1"], "shells": [0.0, 0.15, 0.3],
           "texture": [0.0, 0.1, 0.15],
           # radius spread (relative sigma) and its clip (x R): a crushed sand's wide sizes
           "spread": ["0.12,0.6,1.5", "0.3,0.4,1.8", "0.5,0.3,2"]}
SHORT = {"tomograin": "tg", "skimage": "sk"}
R_SIZES = {8: 96, 12: 128, 20: 192, 40: 320, 60: 448}
METRICS = ["f1", "halves_recovered", "halves", "shells_recovered", "shells", "shell_unlabelled", "over_segmented", "under_segmenting", "under_one_grain", "median_abs_dv",
           "median_abs_dv_reported", "pore_over_segmented_intact", "n_true", "n_pred", "segment_s", "peak_b_per_vox"]


def run(cmd):
    """Runs cmd under GNU time; returns (wall s, CPU s, peak RSS bytes, output).
    GNU time's own fork is small, so the peak is the command's (a child forked
    from this Python process would inherit its resident set into ru_maxrss)."""
    tf = os.path.join(TMP, f"time_{os.getpid()}.txt")
    p = subprocess.run(["/usr/bin/time", "-o", tf, "-f", "%e %U %S %M"] + cmd,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode:
        sys.exit(f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stdout}")
    wall, user, system, kb = open(tf).read().split()[-4:]
    return float(wall), float(user) + float(system), int(kb) * 1024, p.stdout


def scene_name(size, R, s, seed):
    return (f"n{size}_r{R:g}_g{s['gap']:g}_p{s['psf']:g}_c{s['cnr']:g}_po{s['pores'].replace(',', '-')}"
            f"_cu{s['cupping']:g}_d{s['drift']:g}" + (f"_nc{s['corr']:g}" if s["corr"] else "")
            + (f"_e{s['elong']:g}" if s["elong"] != 1.0 else "")
            + (f"_a{s['angular']:g}" if s["angular"] != 0.0 else "")
            + (f"_gc{s['contrast'].split(',')[0]}" if s["contrast"] != "1,1" else "")
            + (f"_sh{s['shells']:g}" if s["shells"] else "")
            + (f"_tx{s['texture']:g}" if s["texture"] else "")
            + (f"_sp{s['spread'].split(',')[0]}" if s["spread"] != MIDDLE["spread"] else "") + f"_s{seed}")


def make_scene(a, prefix, size, R, s, seed):
    if a.reuse and os.path.exists(prefix + ".h5") and (not a.skimage or os.path.exists(prefix + ".tif")):
        return None
    cmd = [PY, os.path.join(HERE, "blind_scene.py"), "-o", prefix, "--size", str(size), "--radius", str(R),
           "--gap", str(s["gap"]), "--psf", str(s["psf"]), "--cnr", str(s["cnr"]), "--pores", s["pores"],
           "--cupping", str(s["cupping"]), "--drift", str(s["drift"]), "--noise-corr", str(s["corr"]), "--elongation", str(s["elong"]),
           "--angularity", str(s["angular"]), "--grain-contrast", s["contrast"], "--shell-frac", str(s["shells"]),
           "--grain-texture", str(s["texture"]),
           "--spread", s["spread"].split(",")[0], "--radius-range", ",".join(s["spread"].split(",")[1:]),
           "--seed", str(seed)]
    if a.skimage:
        cmd.append("--tif")
    wall, cpu, _, _ = run(cmd)
    return wall


def segment_tomograin(a, prefix, R, nvox, truth, table):
    out = os.path.join(a.dir, "seg", os.path.basename(prefix) + f"_tg{a.tag}.h5")
    wall, cpu, rss, _ = run([a.tomograin, "segment", prefix + ".h5:/scan", "-o", out, "--grain-radius-vox", f"{R:g}"]
                            + a.tomograin_args.split())
    summ = json.load(open(out[:-3] + ".segment.json"))
    # The volumes a user gets: `measure --grey` (partial volume from the scan's
    # grey levels, measure/grey_volume.hpp), scored beside the label counts.
    parts = out[:-3] + "_particles.csv"
    mwall, _, _, _ = run([a.tomograin, "measure", out, "--grey", prefix + ".h5:/scan", "-o", parts, "--no-contacts"])
    reported = blind_score.load_reported_volumes(parts, blind_score.label_voxel_m3(out))
    res = blind_score.evaluate(truth, blind_score.load_labels(out, truth.shape), table, reported)
    res.update(segment_s=summ["seconds_total"], measure_wall_s=mwall, wall_s=wall, cpu_s=cpu, peak_b_per_vox=rss / nvox,
               own_peak_b_per_vox=summ.get("peak_rss_bytes_per_voxel"), merges=summ.get("merge", {}).get("merges"))
    return res


def segment_skimage(a, prefix, R, nvox, truth, table):
    out = os.path.join(a.dir, "seg", os.path.basename(prefix) + f"_sk{a.tag}")
    wall, cpu, rss, _ = run([PY, REF, prefix + ".tif", "--out", out, "--radius", f"{R:g}"])
    info = json.load(open(out + "_timing.json"))
    st = {r["stage"]: r for r in info["stages"]}
    seg_s = sum(st[k]["seconds"] for k in ("threshold", "binarise", "fill_pores", "edt", "markers", "watershed", "relabel"))
    res = blind_score.evaluate(truth, blind_score.load_labels(out + "_labels.raw", truth.shape), table)
    os.remove(out + "_labels.raw")   # 4 B/voxel; rerun the peer to see them
    own = max(r["peak_rss_gb"] for r in info["stages"]) * 1e9 / nvox
    res.update(segment_s=seg_s, wall_s=wall, cpu_s=cpu, peak_b_per_vox=rss / nvox, own_peak_b_per_vox=own, merges=None)
    return res


def plan(a):
    """(factor, level, size, R, setting, seed) for every run, middle first."""
    runs = []
    seeds = [int(v) for v in a.seed_list.split(",")] if a.seed_list else list(range(1, a.seeds + 1))
    for sz in a.sizes.split(","):
        size, R = (float(v) for v in sz.split(":"))
        size = int(size)
        for seed in seeds:
            runs.append(("middle", f"{size}^3 R {R:g}", size, R, dict(MIDDLE), seed))
        if a.quick:
            continue
        for fac, levels in FACTORS.items():
            if a.factors and fac not in a.factors.split(","):
                continue
            for lev in levels:
                for seed in seeds:
                    runs.append((fac, lev, size, R, dict(MIDDLE, **{fac: lev}), seed))
    if not a.quick and (not a.factors or "R" in a.factors.split(",")):
        for R, size in R_SIZES.items():
            for seed in seeds[:a.big_seeds] if size > 256 else seeds:
                runs.append(("R", f"{R} ({size}^3)", size, float(R), dict(MIDDLE), seed))
    return runs


def fmt(v, key):
    if v is None:
        return "-"
    if key in ("median_abs_dv", "median_abs_dv_reported", "shell_unlabelled"):
        return f"{100 * v:.2f} %"
    if key in ("f1",):
        return f"{v:.3f}"
    if key == "peak_b_per_vox":
        return f"{v:.1f}"
    if key == "segment_s":
        return f"{v:.2f}"
    return f"{v:.1f}" if abs(v - round(v)) > 1e-9 else str(int(round(v)))


def write_md(a, rows, header):
    pipes = ["tomograin"] + (["skimage"] if a.skimage else [])
    groups = {}
    for r in rows:
        groups.setdefault((r["factor"], str(r["level"])), {}).setdefault(r["pipeline"], []).append(r)
    lines = [header, ""]
    cols = [("F1", "f1"), ("halves rec.", "halves_frac"), ("shells rec.", "shells_frac"),
            ("shell unlabelled", "shell_unlabelled"), ("over", "over_segmented"), ("under", "under_segmenting"),
            ("med. abs dV/V", "median_abs_dv"), ("med. abs dV/V reported", "median_abs_dv_reported"),
            ("pore-over intact", "pore_over_segmented_intact"),
            ("segment s", "segment_s"), ("peak B/vox", "peak_b_per_vox")]
    head = "| factor | level | seeds | particles (true) |"
    for name, _ in cols:
        head += "".join(f" {name} {SHORT[p]} |" for p in pipes)
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    for (fac, lev), by in groups.items():
        line = f"| {fac} | {lev} | {len(by['tomograin'])} | {sum(r['n_true'] for r in by['tomograin']) / len(by['tomograin']):.0f} |"
        for _, key in cols:
            for p in pipes:
                rs = by.get(p, [])
                if key in ("halves_frac", "shells_frac"):
                    what = key.split("_")[0]
                    h = sum(r.get(what) or 0 for r in rs)
                    v = f"{100 * sum(r[what + '_recovered'] for r in rs) / h:.0f} % of {int(h)}" if h else "-"
                else:
                    vals = [r[key] for r in rs if r.get(key) is not None]
                    v = fmt(sum(vals) / len(vals), key) if vals else "-"
                line += f" {v} |"
        lines.append(line)
    lines += ["", "Means over seeds; halves recovered pooled over seeds. tg = tomograin, sk = scikit-image peer.",
              "over: truth particles split into >= 2 labels of >= 20 % each; under: labels holding >= 2 truth",
              "particles >= 20 % each; pore-over intact: over-segmented intact (porous) grains; segment s: tomograin's",
              "seconds_total, the peer's threshold..relabel stages; peak B/vox: the command's max RSS (GNU time) / voxels.",
              "med. abs dV/V: of the label voxel counts; reported: of the volume_mm3 that `tomograin measure --grey`",
              "(and `analyse`) report, the grey-level partial-volume estimate (measure/grey_volume.hpp), same matches."]
    lines += scene_checks(a, groups)
    with open(os.path.join(a.dir, f"sweep{a.tag}.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


def scene_checks(a, groups):
    """What the generator measured on its own scenes (PREFIX.json): solid
    fraction, CNR from the image, split-gap width in the noiseless unblurred
    solid fraction, generation time."""
    lines = ["", "Scenes (blind_scene.py's own measurements, mean over seeds):", "",
             "| factor | level | solid fraction | measured CNR | measured gap (vox) | particles | halves | gen s |",
             "|---|---|---|---|---|---|---|---|"]
    for (fac, lev), by in groups.items():
        infos = []
        for r in by["tomograin"]:
            path = os.path.join(a.dir, "scenes", r["scene"] + ".json")
            if os.path.exists(path):
                infos.append(json.load(open(path)))
        if not infos:
            continue

        def mean(get):
            vals = [v for v in (get(i) for i in infos) if v is not None]
            return sum(vals) / len(vals) if vals else None

        sf = mean(lambda i: i["solid_fraction"])
        cnr = mean(lambda i: (i.get("measured") or {}).get("cnr"))
        gap = mean(lambda i: (i.get("measured_gap_vox") or {}).get("median"))
        npart = mean(lambda i: i["particles"])
        nh = mean(lambda i: i["by_kind"]["half"])
        gen = mean(lambda i: i["seconds"]["total"])
        lines.append(f"| {fac} | {lev} | {sf:.3f} | {'-' if cnr is None else f'{cnr:.2f}'} | "
                     f"{'-' if gap is None else f'{gap:.3f}'} | {npart:.0f} | {nh:.0f} | {gen:.1f} |")
    return lines


def read_csv(path):
    rows = []
    for r in csv.DictReader(open(path)):
        for k, v in r.items():
            if k in ("factor", "level", "pipeline", "scene"):
                continue
            try:
                r[k] = float(v) if v not in ("", "None") else None
            except ValueError:
                pass
        rows.append(r)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tomograin", required=True, help="tomograin program")
    ap.add_argument("-o", "--dir", required=True, help="output folder (scenes, segmentations, sweep.csv, sweep.md)")
    ap.add_argument("--skimage", action="store_true", help="also run the scikit-image peer on every scene")
    ap.add_argument("--tomograin-args", default="",
                    help="extra arguments for tomograin segment, as --tomograin-args='--no-merge --h 0.4' "
                         "(default none: only --grain-radius-vox)")
    ap.add_argument("--tag", default="", help="suffix of the CSV, the table and the segmentations: sweepTAG.csv (none)")
    ap.add_argument("--seeds", type=int, default=3, help="seeds 1..N per point (3)")
    ap.add_argument("--seed-list", help="explicit seeds, e.g. 1,2 (overrides --seeds)")
    ap.add_argument("--big-seeds", type=int, default=2, help="seeds used for scenes larger than 256^3 (2)")
    ap.add_argument("--sizes", default="192:20", help="middle scenes SIZE:R[,SIZE:R...] (192:20)")
    ap.add_argument("--factors", help="only these factors, comma separated (gap,psf,cnr,pores,cupping,drift,corr,elong,angular,contrast,shells,texture,spread,R)")
    ap.add_argument("--quick", action="store_true", help="middle setting only")
    ap.add_argument("--reuse", action="store_true", help="do not regenerate scenes that exist")
    ap.add_argument("--md-only", action="store_true", help="rewrite DIR/sweep.md from DIR/sweep.csv and the scenes, run nothing")
    a = ap.parse_args()
    a.tomograin = os.path.abspath(a.tomograin)
    if a.md_only:
        rows = read_csv(os.path.join(a.dir, f"sweep{a.tag}.csv"))
        a.skimage = any(r["pipeline"] == "skimage" for r in rows)
        write_md(a, rows, open(os.path.join(a.dir, f"sweep{a.tag}.md")).readline().rstrip())
        print(open(os.path.join(a.dir, f"sweep{a.tag}.md")).read())
        return
    os.makedirs(os.path.join(a.dir, "scenes"), exist_ok=True)
    os.makedirs(os.path.join(a.dir, "seg"), exist_ok=True)
    version = subprocess.run([a.tomograin, "--version"], stdout=subprocess.PIPE, text=True).stdout.strip()
    header = (f"# Blind sweep: {a.tomograin} ({version}) segment --grain-radius-vox R {a.tomograin_args}, "
              f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
              f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    done = {}
    rows = []
    csv_path = os.path.join(a.dir, f"sweep{a.tag}.csv")
    keys = ["factor", "level", "size", "R", "seed", "pipeline", "scene", "gen_s", "wall_s", "cpu_s", "own_peak_b_per_vox",
            "merges", "measure_wall_s"] + METRICS + ["intact"]
    with open(csv_path + ".part", "w", newline="") as fcsv:
        w = csv.DictWriter(fcsv, keys, extrasaction="ignore")
        w.writeheader()
        for fac, lev, size, R, s, seed in plan(a):
            name = scene_name(size, R, s, seed)
            prefix = os.path.join(a.dir, "scenes", name)
            if name not in done:
                gen = make_scene(a, prefix, size, R, s, seed)
                truth, table = blind_score.load_truth(prefix)
                nvox = truth.size
                res = {"tomograin": segment_tomograin(a, prefix, R, nvox, truth, table)}
                if a.skimage:
                    res["skimage"] = segment_skimage(a, prefix, R, nvox, truth, table)
                done[name] = (gen, res)
                del truth
            gen, res = done[name]
            for pipe, r in res.items():
                row = dict(r, factor=fac, level=lev, size=size, R=R, seed=seed, pipeline=pipe, scene=name, gen_s=gen)
                rows.append(row)
                w.writerow(row)
                fcsv.flush()
                print(f"{fac:8s} {str(lev):12s} seed {seed} {pipe:9s} F1 {r['f1']:.3f} halves "
                      f"{r['halves_recovered']}/{r['halves']} over {r['over_segmented']} under {r['under_segmenting']} "
                      f"|dV/V| {r['median_abs_dv']:.4f} (reported {r['median_abs_dv_reported'] or float('nan'):.4f}) pore-over {r['pore_over_segmented_intact']} "
                      f"{r['segment_s']:.2f} s {r['peak_b_per_vox']:.1f} B/vox", flush=True)
            write_md(a, rows, header)
    os.replace(csv_path + ".part", csv_path)
    print(open(os.path.join(a.dir, f"sweep{a.tag}.md")).read())


if __name__ == "__main__":
    sys.exit(main())

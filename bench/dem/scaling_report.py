#!/usr/bin/env python3
"""Summarise a bench/dem/scaling.sh folder: results.csv (one row a run),
table.md (the table for RESULTS.md) and scaling.png (particle-steps/s and
bytes per sphere against N, both codes, 1 and 2 cores).
Usage: scaling_report.py OUT_DIR

With repeats (scaling.sh's REPEATS), the table and the plot give each code,
N and core count's run of median loop time; results.csv has every run.

Per run: wall, user, system, CPU share and peak RSS from /usr/bin/time -v;
steps and the stepping loop's wall time (tomograin's summary line, LIGGGHTS'
"Loop time"); particle-steps/s = N steps / loop time; bytes per sphere =
(peak RSS - the same code's 10-sphere run's peak RSS, once per process) / N,
LIGGGHTS on 2 ranks: the sum of the ranks' peaks; mean coordination
number over the timed window = 2 x sphere-sphere contacts / N averaged over
the rows after step 0 (tomograin history.csv `contacts`; LIGGGHTS
compute contact/atom summed = 2 x contacts)."""
import csv
import glob
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def time_v(path):
    t = {}
    for line in open(path):
        k, _, v = line.strip().partition(": ")
        t[k] = v
    w = t["Elapsed (wall clock) time (h:mm:ss or m:ss)"].split(":")
    wall = sum(float(x) * 60**i for i, x in enumerate(reversed(w)))
    return {"wall_s": wall, "user_s": float(t["User time (seconds)"]), "sys_s": float(t["System time (seconds)"]),
            "cpu_pct": float(t["Percent of CPU this job got"].rstrip("%")),
            "rss_kb": int(t["Maximum resident set size (kbytes)"])}


def tomograin_run(d, n, workers):
    r = time_v(os.path.join(d + ".in", "time.txt"))
    out = open(os.path.join(d + ".in", "stdout.txt")).read()
    m = re.search(r"(\d+) steps\n.*wall ([0-9.]+) s, ([0-9.e+]+) particle-steps/s", out)
    r["steps"], r["loop_s"] = int(m.group(1)), float(m.group(2))
    rows = list(csv.DictReader(open(os.path.join(d, "history.csv"))))
    cn = [2 * float(x["contacts"]) / n for x in rows if float(x["step"]) > 0]
    r["cn"] = sum(cn) / len(cn) if cn else float("nan")
    r.update(code="tomograin", n=n, workers=workers, processes=1)
    return r


def liggghts_run(d, n, workers):
    r = time_v(os.path.join(d, "time.txt"))
    ranks = sorted(glob.glob(os.path.join(d, "rank*.time")))
    if ranks:  # mpirun: memory = the sum of the ranks' peaks
        r["rss_kb"] = sum(time_v(f)["rss_kb"] for f in ranks)
    r["processes"] = max(1, len(ranks))
    scr = open(os.path.join(d, "screen")).read()
    m = list(re.finditer(r"Loop time of ([0-9.e+-]+) on \d+ procs for (\d+) steps", scr))[-1]  # the timed run
    r["loop_s"], r["steps"] = float(m.group(1)), int(m.group(2))
    # Thermo rows of the timed run: "step atoms nc cpu" after its header.
    body = scr[scr.rindex("Step    Atoms             nc"):m.start()]
    cn = [float(l.split()[2]) / n for l in body.splitlines()[1:] if l.split() and l.split()[0].isdigit() and int(l.split()[0]) > 0]
    r["cn"] = sum(cn) / len(cn) if cn else float("nan")
    r.update(code="liggghts", n=n, workers=workers)
    return r


def main():
    out = sys.argv[1]
    runs = []
    # Run folders: CODE_N_WORKERS, and CODE_N_WORKERS_rK for repeat K > 1.
    def name(d):
        parts = os.path.basename(d).split("_")
        return parts[0], int(parts[1]), parts[2], int(parts[3][1:]) if len(parts) > 3 else 1
    def folders(*patterns):  # the run folders (tomograin's inputs are in FOLDER.in)
        return sorted(d for p in patterns for d in glob.glob(os.path.join(out, p)) if not d.endswith(".in"))
    for d in folders("tg_*_t[12]", "tg_*_t[12]_r*", "tgskin0_*_t1"):
        tag, n, t, rep = name(d)
        runs.append(tomograin_run(d, n, int(t[1:])))
        runs[-1]["repeat"] = rep
        if tag == "tgskin0":
            runs[-1]["code"] = "tomograin skin 0"
    for d in folders("lg_*_np[12]", "lg_*_np[12]_r*"):
        _, n, p, rep = name(d)
        if os.path.exists(os.path.join(d, "time.txt")):
            runs.append(liggghts_run(d, n, int(p[2:])))
            runs[-1]["repeat"] = rep
    base = {r["code"]: r["rss_kb"] for r in runs if r["n"] == 10}
    base["tomograin skin 0"] = base.get("tomograin", 0)
    runs = [r for r in runs if r["n"] > 10]
    for r in runs:
        r["psteps_per_s"] = r["n"] * r["steps"] / r["loop_s"]
        r["ns_per_sphere_step"] = 1e9 / r["psteps_per_s"]
        r["bytes_per_sphere"] = (r["rss_kb"] - r["processes"] * base.get(r["code"], 0)) * 1024 / r["n"]
    runs.sort(key=lambda r: (r["code"] == "tomograin skin 0", r["n"], r["workers"], r["code"] != "tomograin", r["repeat"]))
    cols = ["code", "n", "workers", "repeat", "steps", "loop_s", "wall_s", "user_s", "sys_s", "cpu_pct", "rss_kb", "psteps_per_s",
            "bytes_per_sphere", "cn", "ns_per_sphere_step"]
    with open(os.path.join(out, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(runs)
    # One row per code, N and core count: the run of median loop time (the
    # range over the repeats beside it), and the ratio of the medians with
    # the range of the paired ratios (repeat K of one code against repeat K
    # of the other, made a minute apart).
    groups = {}
    for r in runs:
        groups.setdefault((r["code"], r["n"], r["workers"]), []).append(r)

    def median_run(rs):
        return sorted(rs, key=lambda r: r["loop_s"])[(len(rs) - 1) // 2]

    lines = ["| N | cores | code | runs | steps | loop s (median; range) | process wall s | user s | CPU | peak RSS MB | "
             "bytes/sphere | particle-steps/s | tomograin / LIGGGHTS (medians; paired range) | mean CN |", "|" + "---|" * 14]
    for (code, n, workers), rs in groups.items():
        r = median_run(rs)
        other = groups.get(("liggghts", n, workers))
        ratio = ""
        if code == "tomograin" and other:
            ratio = "**%.2fx**" % (median_run(other)["loop_s"] / r["loop_s"])
            lg = {o["repeat"]: o for o in other}
            paired = sorted(lg[t["repeat"]]["loop_s"] / t["loop_s"] for t in rs if t["repeat"] in lg)
            if len(paired) > 1:
                ratio += " (%.2f-%.2f)" % (paired[0], paired[-1])
        spread = " (%.2f-%.2f)" % (min(t["loop_s"] for t in rs), max(t["loop_s"] for t in rs)) if len(rs) > 1 else ""
        lines.append("| %d | %d | %s | %d | %d | %.2f%s | %.1f | %.1f | %d %% | %.0f | %.0f | %.3g | %s | %.2f |" % (
            n, workers, code, len(rs), r["steps"], r["loop_s"], spread, r["wall_s"], r["user_s"], r["cpu_pct"],
            r["rss_kb"] / 1024, r["bytes_per_sphere"], r["psteps_per_s"], ratio, r["cn"]))
    lines.append("")
    lines.append("Baselines (10 spheres): " + ", ".join("%s %.1f MB" % (k, v / 1024) for k, v in sorted(base.items())))
    open(os.path.join(out, "table.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for code, mk in (("tomograin", "o"), ("liggghts", "s"), ("tomograin skin 0", "^")):
        for wk, ls in ((1, "-"), (2, "--")):
            rs = sorted((median_run(g) for (c, _, w), g in groups.items() if c == code and w == wk), key=lambda r: r["n"])
            if not rs:
                continue
            lab = "%s, %d %s" % ("LIGGGHTS 3.8" if code == "liggghts" else code, wk,
                                 ("rank" if wk == 1 else "ranks") if code == "liggghts" else ("thread" if wk == 1 else "threads"))
            ax[0].plot([r["n"] for r in rs], [r["psteps_per_s"] for r in rs], ls, marker=mk, label=lab)
            ax[1].plot([r["n"] for r in rs], [r["bytes_per_sphere"] for r in rs], ls, marker=mk, label=lab)
    for a, yl in ((ax[0], "particle-steps per second"), (ax[1], "bytes per sphere (peak RSS - 10-sphere run) / N")):
        a.set_xscale("log")
        a.set_xlabel("spheres N")
        a.set_ylabel(yl)
        a.grid(True, which="both", alpha=0.3)
        a.set_ylim(bottom=0)
    ax[0].legend(fontsize=8)
    ax[0].set_title("throughput (stepping loop)")
    ax[1].set_title("memory per sphere")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scaling.png"), dpi=110)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""workflow/Snakefile on a tiny campaign, locally (issue 24).

Two synthetic studies (SIZE^3, 2 stages; the first with the tests' tiny DEM
cell, so it has a DEM run and a comparison) are run
  - by hand: `tomograin run` of each study into smk/, then moved to direct/;
  - by Snakemake: `snakemake --cores 2` into smk/
(the same path: outputs name their own files, e.g. psd_summary.csv's `file`
column, and each step's key hashes its arguments).
Checks:
  1. one job per step of each study's plan (asked of `tomograin run --plan`)
     plus the campaign summary, and the study folders identical to the ones
     run by hand (same_outputs.py: HDF5 by dataset, JSON without timing
     fields, the rest byte for byte);
  2. campaign.csv is every study's summary.csv row for row with the study's
     name in front (read back independently with the csv module);
     campaign.png is a PNG;
  3. a second run has nothing to do and touches no file;
  4. with one record removed (`track` of the first study), Snakemake reruns
     exactly that step, the steps that need it (closure of the plan's
     `needs`) and the campaign summary, and the folders are again identical;
  5. bad input: a config without `out`, a study file tomograin refuses
     (the workflow stops at parse time with tomograin's one-line error,
     nothing written); campaign_summary.py with a missing summary.csv (exit 2,
     one line naming the file, no campaign.csv or .png).

Usage: workflow_test.py TOMOGRAIN [SIZE=48]
"""
import csv
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import pyharness as H  # noqa: E402
from pyharness import TG, check  # noqa: E402

sys.path.insert(0, HERE)
import same_outputs  # noqa: E402

ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SNAKEFILE = os.path.join(ROOT, "workflow", "Snakefile")
SUMMARY_PY = os.path.join(ROOT, "workflow", "scripts", "campaign_summary.py")
SIZE = sys.argv[2] if len(sys.argv) > 2 else "48"


def snakemake(workdir, *args):
    return subprocess.run(["snakemake", "-s", SNAKEFILE, "--cores", "2", "-d", workdir] + list(args),
                          capture_output=True, text=True, env=H.ENV)


def plans(cfg_studies, out):
    """key -> plan of every study, from tomograin itself."""
    out_plans = {}
    for f in cfg_studies:
        key = os.path.splitext(os.path.basename(f))[0]
        r = subprocess.run([TG, "run", f, "-o", os.path.join(out, key), "--plan"], capture_output=True, text=True)
        out_plans[key] = json.loads(r.stdout)
    return out_plans


def jobs_run(log):
    """(study, step) of every job Snakemake ran, from its log ('wildcards: study=a, step=track')."""
    return sorted((m.group(1), m.group(2)) for m in re.finditer(r"wildcards: study=([^,\s]+), step=(\S+)", log)) + \
        [("", "campaign")] * log.count("rule campaign:")


def mtimes(d):
    out = {}
    for root, _, fs in os.walk(d):
        for f in fs:
            p = os.path.join(root, f)
            out[p] = os.stat(p).st_mtime_ns
    return out


def main():
    with H.workdir("tg_workflow_") as w:
        r = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "workflow", "scripts", "make_synthetic_campaign.py"),
                            TG, "c", "--studies", "2", "--size", SIZE, "--stages", "2", "--dem", "1"],
                           capture_output=True, text=True)
        check(r.returncode == 0, "synthetic campaign written" + (f": {r.stderr}" if r.returncode else ""))
        cfg = os.path.join(w, "c", "campaign.yaml")
        studies = [os.path.join(w, "c", "studies", f"s0{i}.toml") for i in (1, 2)]
        with open(cfg, "w") as f:
            f.write("studies:\n" + "".join(f"  - {s}\n" for s in studies) + f"out: {w}/smk\ntomograin: {TG}\n")
        plan = plans(studies, os.path.join(w, "smk"))
        check(any(s["id"].startswith("dem") for s in plan["s01"]["steps"]),
              f"study s01 has a DEM step: {[s['id'] for s in plan['s01']['steps']]}")

        # 1. By hand and by Snakemake: the same folders, one job per step.
        t0 = time.monotonic()
        # Both write to smk/ (outputs hold their own paths, e.g. psd_summary.csv's
        # `file`, and each step's key hashes its arguments): the run by hand first,
        # then moved to direct/.
        for s in studies:
            key = os.path.splitext(os.path.basename(s))[0]
            r = subprocess.run([TG, "run", s, "-o", os.path.join(w, "smk", key)], capture_output=True, text=True,
                               env=H.ENV)
            check(r.returncode == 0, f"tomograin run {key}" + (f": {r.stderr.strip()}" if r.returncode else ""))
        t_hand = time.monotonic() - t0
        os.rename(os.path.join(w, "smk"), os.path.join(w, "direct"))
        t0 = time.monotonic()
        r = snakemake(os.path.join(w, "wd"), "--configfile", cfg)
        t_smk = time.monotonic() - t0
        check(r.returncode == 0, f"snakemake --cores 2 ({t_smk:.1f} s; by hand {t_hand:.1f} s)"
              + (f": {r.stderr[-2000:]}" if r.returncode else ""))
        if r.returncode:
            return
        ran = jobs_run(r.stdout + r.stderr)
        want = sorted((k, s["id"]) for k, p in plan.items() for s in p["steps"]) + [("", "campaign")]
        check(ran == want, f"one job per planned step + campaign ({len(ran)} jobs, {len(want)} planned)")
        for key in plan:
            d = same_outputs.diffs(os.path.join(w, "direct", key), os.path.join(w, "smk", key))
            n = len(same_outputs.files(os.path.join(w, "direct", key)))
            check(not d and n > 0, f"{key}: {n} files identical by hand and by snakemake" + (f"; {list(d.items())[:5]}" if d else ""))

        # 2. campaign.csv = the summaries, row for row; campaign.png a PNG.
        expected = []
        for key, p in plan.items():
            summ = [s for s in p["steps"] if s["id"] == "summary"][0]["outputs"][0]
            summ = summ if summ.endswith(".csv") else os.path.join(summ, "summary.csv")
            with open(summ, newline="") as f:
                expected += [{k: v for k, v in dict(row, study=p["study"]).items() if v != ""}
                             for row in csv.DictReader(f)]
        with open(os.path.join(w, "smk", "campaign.csv"), newline="") as f:
            got = list(csv.DictReader(f))
        got = [{k: v for k, v in row.items() if v != ""} for row in got]
        check(got == expected and len(got) > 0, f"campaign.csv holds the {len(expected)} summary rows of both studies")
        with open(os.path.join(w, "smk", "campaign.png"), "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", "campaign.png is a PNG")

        # 3. Nothing to do the second time, nothing touched.
        before = mtimes(os.path.join(w, "smk"))
        r = snakemake(os.path.join(w, "wd"), "--configfile", cfg)
        check(r.returncode == 0 and "Nothing to be done" in r.stdout + r.stderr, "second run: nothing to be done")
        check(mtimes(os.path.join(w, "smk")) == before, "second run: no file touched")

        # 4. A removed record reruns that step, the steps after it, and the summary.
        needs = {s["id"]: s["needs"] for s in plan["s01"]["steps"]}
        redo = {"track"}
        while True:
            more = {i for i, n in needs.items() if redo & set(n)} - redo
            if not more:
                break
            redo |= more
        os.remove(os.path.join(w, "smk", "s01", ".run", "track.json"))
        r = snakemake(os.path.join(w, "wd"), "--configfile", cfg)
        ran = jobs_run(r.stdout + r.stderr)
        want = sorted(("s01", i) for i in redo) + [("", "campaign")]
        check(r.returncode == 0 and ran == want, f"record of track removed: reruns {[j[1] for j in want]} (ran {[j[1] for j in ran]})")
        d = same_outputs.diffs(os.path.join(w, "direct", "s01"), os.path.join(w, "smk", "s01"))
        check(not d, "s01 still identical to the run by hand" + (f"; {list(d.items())[:5]}" if d else ""))

        # 5. Bad input.
        bad_cfg = os.path.join(w, "bad.yaml")
        with open(bad_cfg, "w") as f:
            f.write(f"studies: [{studies[0]}]\ntomograin: {TG}\n")
        r = snakemake(os.path.join(w, "wd_bad"), "--configfile", bad_cfg)
        check(r.returncode != 0 and "'out' is missing" in r.stderr, "config without out: refused, naming the key")
        bad_study = os.path.join(w, "c", "studies", "bad.toml")
        with open(bad_study, "w") as f:
            f.write(open(studies[1]).read().replace("strain = 0.044", "strain = -1.0"))
        with open(bad_cfg, "w") as f:
            f.write(f"studies: [{bad_study}]\nout: {w}/bad_out\ntomograin: {TG}\n")
        r = snakemake(os.path.join(w, "wd_bad"), "--configfile", bad_cfg)
        check(r.returncode != 0 and "bad.toml" in r.stderr and not os.path.exists(os.path.join(w, "bad_out")),
              "study tomograin refuses: stops at parse time, names the file, writes nothing")
        out_csv = os.path.join(w, "x.csv")
        r = subprocess.run(["/usr/bin/python3", SUMMARY_PY, "-o", out_csv, "--plot", os.path.join(w, "x.png"),
                            f"a={w}/direct/s01/summary/summary.csv", f"b={w}/nowhere/summary.csv"],
                           capture_output=True, text=True)
        lines = r.stderr.strip().splitlines()
        check(r.returncode == 2 and len(lines) == 1 and "nowhere/summary.csv" in lines[0]
              and not os.path.exists(out_csv) and not os.path.exists(os.path.join(w, "x.png")),
              f"campaign_summary.py, missing summary.csv: exit 2, one line, nothing written ({lines})")


main()
H.finish()

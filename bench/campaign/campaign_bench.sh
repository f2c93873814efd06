#!/usr/bin/env bash
# A campaign of 8 synthetic studies (128^3, 3 stages each, no DEM) two ways on
# this machine (issue 24):
#   by hand     `tomograin run` of each study, one after the other
#   snakemake   workflow/Snakefile with --cores 2 (one job per step)
# Prints wall, user and system time of each (CPU share = (user + sys) / wall),
# the machine's load, and the workflow's overhead per job:
#   tomograin   job wall (Snakemake's benchmark file) - the step's own time
#               (its record's "seconds"): process start, reading the study,
#               hashing inputs for the step's key
#   scheduling  (2 cores x snakemake wall - sum of threads x job wall) / jobs:
#               core-seconds per job that no job held (Snakemake's start,
#               parsing with one `--plan` per study, job dispatch and polling)
# plus the time of a Snakemake run with nothing to do (start + 8 plans + DAG),
# and checks that both ways give identical study folders.
# Usage: bench/campaign/campaign_bench.sh TOMOGRAIN [WORKDIR] [STUDIES=8] [SIZE=128]
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../.." && pwd)
TG=$(realpath "${1:?usage: $0 TOMOGRAIN [WORKDIR] [STUDIES] [SIZE]}")
W=${2:-$(mktemp -d /tmp/tg_campaign_bench_XXXXXX)}
N=${3:-8}
SIZE=${4:-128}
mkdir -p "$W"
W=$(cd "$W" && pwd)
PY=/usr/bin/python3
CORES=2
"$REPO/scripts/install_deps.sh" --campaign

echo "== $(date -u +%FT%TZ) $(git -C "$REPO" rev-parse --short HEAD); snakemake $(snakemake --version); $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB"
$PY "$REPO/workflow/scripts/make_synthetic_campaign.py" "$TG" "$W/campaign" --studies "$N" --size "$SIZE" --stages 3
mapfile -t STUDIES < <(ls "$W"/campaign/studies/*.toml)

TIMEFORMAT='%R %U %S'
load() { cut -d' ' -f1 /proc/loadavg; }

l0=$(load)
# Both ways write to the same OUT (outputs name their own files, e.g.
# psd_summary.csv's `file` column; each step's key hashes its arguments); the
# run by hand is moved to $W/hand afterwards.
OUT=$W/campaign/out
{ time for s in "${STUDIES[@]}"; do
    TOMOGRAIN_QUIET=1 "$TG" run "$s" -o "$OUT/$(basename "$s" .toml)" > /dev/null
  done; } 2> "$W/hand.time"
mv "$OUT" "$W/hand"
l1=$(load)
{ time snakemake -s "$REPO/workflow/Snakefile" --configfile "$W/campaign/campaign.yaml" \
    --cores $CORES -d "$W/smk_wd" > "$W/smk.log" 2>&1; } 2> "$W/smk.time"
l2=$(load)
{ time snakemake -s "$REPO/workflow/Snakefile" --configfile "$W/campaign/campaign.yaml" \
    --cores $CORES -d "$W/smk_wd" > "$W/smk_nothing.log" 2>&1; } 2> "$W/smk_nothing.time"
grep -q "Nothing to be done" "$W/smk_nothing.log" || { echo "FAIL: a second run had work to do"; exit 1; }

$PY - "$W" "$CORES" "$l0" "$l1" "$l2" <<'EOF'
import csv, glob, json, os, sys
w, cores = sys.argv[1], int(sys.argv[2])
loads = sys.argv[3:6]
def t(name):
    r, u, s = map(float, open(os.path.join(w, name)).read().split()[-3:])
    return r, u, s
for label, name, l in (("by hand (tomograin run x N)", "hand.time", loads[0]),
                       (f"snakemake --cores {cores}", "smk.time", loads[1])):
    r, u, s = t(name)
    print(f"{label:34s} wall {r:7.1f} s  user {u:7.1f} s  sys {s:5.1f} s  CPU share {(u + s) / r / cores * 100:5.1f} % of {cores} cores  (load before {l})")
print(f"{'snakemake, nothing to do':34s} wall {t('smk_nothing.time')[0]:7.1f} s  (start, one --plan per study, DAG)")
jobs = []
for b in glob.glob(os.path.join(w, "campaign", "out", "benchmarks", "*", "*.tsv")):
    study, step = b.split(os.sep)[-2], os.path.basename(b)[:-4]
    row = next(csv.DictReader(open(b), delimiter="\t"))
    rec = json.load(open(os.path.join(w, "campaign", "out", study, ".run", step + ".json")))
    jobs.append((study, step, float(row["s"]), float(rec["seconds"]), float(row["max_rss"])))
# Threads per job: the plan's (capped at --cores, as Snakemake does).
import subprocess, yaml
cfg = yaml.safe_load(open(os.path.join(w, "campaign", "campaign.yaml")))
threads = {}
for f in cfg["studies"]:
    key = os.path.splitext(os.path.basename(f))[0]
    plan = json.loads(subprocess.run([cfg["tomograin"], "run", f, "-o", os.path.join(w, "campaign", "out", key), "--plan"],
                                     capture_output=True, text=True, check=True).stdout)
    for s in plan["steps"]:
        threads[(key, s["id"])] = min(s["threads"], cores)
n = len(jobs)
wall = t("smk.time")[0]
sum_job = sum(j[2] for j in jobs)
sum_step = sum(j[3] for j in jobs)
busy = sum(j[2] * threads[(j[0], j[1])] for j in jobs)
print(f"jobs {n} (+ campaign summary); sum of job walls {sum_job:.1f} s, of the steps' own times {sum_step:.1f} s")
print(f"overhead per job: tomograin run --only {(sum_job - sum_step) / n:.2f} s; "
      f"scheduling {(cores * wall - busy) / n:.2f} core-s ({(cores * wall - busy) / cores / n:.2f} s of wall)")
by_step = {}
for study, step, s, own, rss in jobs:
    kind = step.split("-")[0]
    by_step.setdefault(kind, []).append((s, own, rss))
for kind, v in sorted(by_step.items()):
    print(f"  {kind:10s} x{len(v):2d}: job {sum(x[0] for x in v) / len(v):6.2f} s, step {sum(x[1] for x in v) / len(v):6.2f} s, "
          f"peak RSS {max(x[2] for x in v):7.1f} MB, threads {threads[next((k for k in threads if k[1].split('-')[0] == kind))]}")
EOF
ok=1
for d in "$W"/hand/*; do
  $PY "$REPO/tests/workflow/same_outputs.py" "$d" "$OUT/$(basename "$d")" > "$W/same_$(basename "$d").txt" || ok=0
done
[[ $ok -eq 1 ]] && echo "ok   every study folder identical by hand and by snakemake" \
  || { echo "FAIL study folders differ (see $W/same_*.txt)"; exit 1; }
echo "work folder: $W"

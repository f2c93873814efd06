#!/usr/bin/env bash
# A campaign of 8 synthetic studies (128^3, 3 stages each, no DEM: 3 analyse
# steps, track, summary) two ways on this machine (issue 24):
#   by hand     `tomograin run` of each study, one after the other
#   snakemake   workflow/Snakefile with --cores 2 (one job per step, plus the
#               campaign summary)
# REPS times each, interleaved (hand, snakemake, hand, ...), since the machine
# is shared and its load drifts. Per run: wall, user + sys (CPU share of the 2
# cores), the load average before, and the sum of the steps' own times (each
# record's "seconds": the same work both ways). Then, from those:
#   overhead per job, snakemake vs by hand
#       ((snakemake wall - its steps) - (hand wall - its steps)) / jobs:
#       what the workflow adds per job beyond running the same steps in one
#       `tomograin run` per study; the step times themselves drift with the
#       load, and are taken out
#   of which `tomograin run --only` itself
#       (job wall in Snakemake's benchmark file - the step's own time) / jobs:
#       a process per step (start, reading the study, the step's key)
# plus a Snakemake run with nothing to do (start, one --plan per study, the
# DAG), and a check that both ways give identical study folders.
# Usage: bench/campaign/campaign_bench.sh TOMOGRAIN [WORKDIR] [STUDIES=8] [SIZE=128] [REPS=3]
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../.." && pwd)
TG=$(realpath "${1:?usage: $0 TOMOGRAIN [WORKDIR] [STUDIES] [SIZE] [REPS]}")
W=${2:-$(mktemp -d /tmp/tg_campaign_bench_XXXXXX)}
N=${3:-8}
SIZE=${4:-128}
REPS=${5:-3}
mkdir -p "$W"
W=$(cd "$W" && pwd)
PY=/usr/bin/python3
CORES=2
"$REPO/scripts/install_deps.sh" --campaign

echo "== $(date -u +%FT%TZ) $(git -C "$REPO" rev-parse --short HEAD); snakemake $(snakemake --version); $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB"
$PY "$REPO/workflow/scripts/make_synthetic_campaign.py" "$TG" "$W/campaign" --studies "$N" --size "$SIZE" --stages 3
mapfile -t STUDIES < <(ls "$W"/campaign/studies/*.toml)
SNAKE=(snakemake -s "$REPO/workflow/Snakefile" --configfile "$W/campaign/campaign.yaml" --cores $CORES -d "$W/smk_wd")
# Both ways write to the same OUT (outputs name their own files, e.g.
# psd_summary.csv's `file` column; each step's key hashes its arguments); each
# run's folder is moved to $W/<way>_<rep> afterwards.
OUT=$W/campaign/out
TIMEFORMAT='%R %U %S'
rm -rf "$OUT" "$W"/hand_* "$W"/smk_*

for r in $(seq "$REPS"); do
  cut -d' ' -f1 /proc/loadavg > "$W/hand_$r.load"
  { time for s in "${STUDIES[@]}"; do
      TOMOGRAIN_QUIET=1 "$TG" run "$s" -o "$OUT/$(basename "$s" .toml)" > /dev/null
    done; } 2> "$W/hand_$r.time"
  mv "$OUT" "$W/hand_$r"
  cut -d' ' -f1 /proc/loadavg > "$W/smk_$r.load"
  rm -rf "$W/smk_wd"
  { time "${SNAKE[@]}" > "$W/smk_$r.log" 2>&1; } 2> "$W/smk_$r.time"
  if [[ $r -eq "$REPS" ]]; then
    { time "${SNAKE[@]}" > "$W/smk_nothing.log" 2>&1; } 2> "$W/smk_nothing.time"
    grep -q "Nothing to be done" "$W/smk_nothing.log" || { echo "FAIL: a second run had work to do"; exit 1; }
  fi
  mv "$OUT" "$W/smk_$r"
done

$PY - "$W" "$CORES" "$REPS" <<'EOF'
import csv, glob, json, os, statistics, sys
w, cores, reps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])


def times(name):
    return tuple(map(float, open(os.path.join(w, name + ".time")).read().split()[-3:]))


def step_seconds(d):
    recs = [f for f in glob.glob(os.path.join(d, "*", ".run", "*.json")) if not f.endswith("hashes.json")]
    return len(recs), sum(json.load(open(f))["seconds"] for f in recs)


rows = []
for r in range(1, reps + 1):
    for way in ("hand", "smk"):
        wall, user, sys_ = times(f"{way}_{r}")
        n, steps = step_seconds(os.path.join(w, f"{way}_{r}"))
        load = open(os.path.join(w, f"{way}_{r}.load")).read().strip()
        jobs = 0.0
        for b in glob.glob(os.path.join(w, f"{way}_{r}", "benchmarks", "*", "*.tsv")):
            jobs += float(next(csv.DictReader(open(b), delimiter="\t"))["s"])
        rows.append((r, way, wall, user + sys_, load, n, steps, jobs))
        label = "by hand (tomograin run x studies)" if way == "hand" else f"snakemake --cores {cores}"
        print(f"rep {r} {label:34s} wall {wall:6.1f} s  CPU {(user + sys_) / wall / cores * 100:5.1f} % of {cores} cores"
              f"  load before {load:5s}  steps {n} x, own time {steps:6.1f} s"
              + (f", job walls {jobs:6.1f} s" if way == "smk" else ""))
print(f"snakemake, nothing to do: wall {times('smk_nothing')[0]:.1f} s (start, one --plan per study, DAG)")
hand = [x for x in rows if x[1] == "hand"]
smk = [x for x in rows if x[1] == "smk"]
n = smk[0][5] + 1  # the steps + the campaign summary
med = statistics.median
print(f"median wall: by hand {med(x[2] for x in hand):.1f} s, snakemake {med(x[2] for x in smk):.1f} s "
      f"({n} jobs: {smk[0][5]} steps + campaign summary)")
per_job = [((s[2] - s[6]) - (h[2] - h[6])) / n for h, s in zip(hand, smk)]
only = [(s[7] - s[6]) / smk[0][5] for s in smk]
print(f"overhead per job, snakemake vs by hand: {', '.join(f'{x:.2f}' for x in per_job)} s (median {med(per_job):.2f} s)")
print(f"  of which tomograin run --only (job wall - step's own time): {', '.join(f'{x:.2f}' for x in only)} s "
      f"(median {med(only):.2f} s)")
EOF
ok=1
for d in "$W"/hand_1/*/; do
  s=$(basename "$d")
  $PY "$REPO/tests/workflow/same_outputs.py" "$d" "$W/smk_1/$s" > "$W/same_$s.txt" || ok=0
done
[[ $ok -eq 1 ]] && echo "ok   every study folder identical by hand and by snakemake (rep 1)" \
  || { echo "FAIL study folders differ (see $W/same_*.txt)"; exit 1; }
echo "work folder: $W"

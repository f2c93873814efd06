#!/usr/bin/env bash
# The workflow on a real SLURM cluster (issue 24): a one-node cluster on this
# machine (slurm_cluster.sh), a small campaign run once locally
# (`snakemake --cores 2`) and once through sbatch (the profile
# workflow/profiles/slurm, unchanged Snakefile), then:
#   - every job ran through SLURM: the controller's job log (jobcomp/filetxt;
#     there is no slurmdbd, so no sacct) holds exactly one COMPLETED job, exit
#     0:0, per step of every study's plan (asked of `tomograin run --plan`, not
#     of Snakemake) plus the campaign summary, each with the CPUs and memory
#     its step declares;
#   - the outputs are identical to the local run's (tests/workflow/same_outputs.py:
#     HDF5 by dataset and attribute, JSON without timing fields, the rest byte
#     for byte);
# and the daemons are stopped (also on failure). Prints how long each part took.
#
# The campaign: two synthetic studies (96^3, 3 stages each, seeds 1 and 2);
# the first also runs a 4-variant DEM sweep on the tests' tiny cell (4 DEM runs
# + 4 comparisons), the second has no DEM.
#
# Needs root (slurmd) and installs Snakemake, slurm-wlm and munge when missing
# (scripts/install_deps.sh --campaign). Too slow for `make test` (minutes).
# Usage: bench/campaign/slurm_test.sh TOMOGRAIN [WORKDIR]   (WORKDIR kept; default a new temp folder)
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../.." && pwd)
TG=$(realpath "${1:?usage: $0 TOMOGRAIN [WORKDIR]}")
W=${2:-$(mktemp -d /tmp/tg_slurm_test_XXXXXX)}
mkdir -p "$W"
W=$(cd "$W" && pwd)
PY=/usr/bin/python3
SNAKE=(snakemake -s "$REPO/workflow/Snakefile" --configfile "$W/campaign/campaign.yaml")

"$REPO/scripts/install_deps.sh" --campaign

declare -a PARTS
now() { date +%s.%N; }
part() {  # part NAME START: remember how long NAME took
  PARTS+=("$(awk -v n="$1" -v a="$2" -v b="$(now)" 'BEGIN { printf "%-34s %7.1f s", n, b - a }')")
}

t=$(now)
$PY "$REPO/workflow/scripts/make_synthetic_campaign.py" "$TG" "$W/campaign" --studies 2 --size 96 --stages 3 --dem 4
part "inputs (synth 2 x 3 scans)" "$t"

# Both runs write to the same OUT (outputs name their own files, e.g.
# psd_summary.csv's `file` column; each step's key hashes its arguments): the
# local run's is moved to $W/local afterwards.
t=$(now)
"${SNAKE[@]}" --cores 2 -d "$W/smk_local" > "$W/local.log" 2>&1 \
  || { tail -n 30 "$W/local.log"; echo "FAIL: local run (log $W/local.log)"; exit 1; }
mv "$W/campaign/out" "$W/local"
part "local run (snakemake --cores 2)" "$t"

t=$(now)
trap '"$REPO/bench/campaign/slurm_cluster.sh" stop "$W/cluster"' EXIT
eval "$("$REPO/bench/campaign/slurm_cluster.sh" start "$W/cluster")"   # sets SLURM_CONF
part "cluster start" "$t"

t=$(now)
"${SNAKE[@]}" --profile "$REPO/workflow/profiles/slurm" -d "$W/smk_slurm" \
  > "$W/slurm.log" 2>&1 || { tail -n 30 "$W/slurm.log"; echo "FAIL: SLURM run (log $W/slurm.log)"; exit 1; }
part "SLURM run (profile, sbatch)" "$t"

t=$(now)
fail=0
# Every job of the plans, once, through SLURM, with its resources.
$PY - "$TG" "$W/campaign/campaign.yaml" "$W/campaign/out" "$W/cluster/jobcomp.log" <<'EOF' || fail=1
import collections, json, os, subprocess, sys, yaml
tg, cfg_file, out, log = sys.argv[1:]
cfg = yaml.safe_load(open(cfg_file))
expected = {}  # (study, step) -> (cpus, mem_mb)
for f in cfg["studies"]:
    key = os.path.splitext(os.path.basename(f))[0]
    plan = json.loads(subprocess.run([tg, "run", f, "-o", os.path.join(out, key), "--plan"],
                                     capture_output=True, text=True, check=True).stdout)
    for s in plan["steps"]:
        expected[(key, s["id"])] = (s["threads"], s["mem_mb"])
expected[("", "campaign")] = (1, 500)  # the summary rule's resources (workflow/Snakefile)
jobs = collections.Counter()
bad = []
for line in open(log):
    f = dict(x.split("=", 1) for x in line.split() if "=" in x)
    name = f.get("Name", "")
    if not name.startswith("tg-"):
        continue
    rule, _, wc = name[3:].partition("-")
    w = dict(x.split("=", 1) for x in wc.split(",") if "=" in x)
    job = (w.get("study", ""), w.get("step", rule))
    jobs[job] += 1
    tres = dict(x.split("=", 1) for x in f.get("Tres", "").split(","))
    want = expected.get(job)
    if f.get("JobState") != "COMPLETED" or f.get("ExitCode") != "0:0":
        bad.append(f"{job}: {f.get('JobState')} exit {f.get('ExitCode')}")
    elif want and (int(tres.get("cpu", -1)) != want[0] or tres.get("mem") != f"{want[1]}M"):
        bad.append(f"{job}: got cpu={tres.get('cpu')} mem={tres.get('mem')}, declared {want}")
missing = sorted(set(expected) - set(jobs))
extra = sorted(set(jobs) - set(expected))
twice = sorted(j for j, n in jobs.items() if n > 1)
ok = not (missing or extra or twice or bad)
print(f"{'ok  ' if ok else 'FAIL'} {sum(jobs.values())} SLURM jobs for {len(expected)} planned jobs"
      f" ({len(expected) - 1} steps + campaign); all COMPLETED 0:0 with the declared CPUs and memory")
for what, v in (("missing", missing), ("not planned", extra), ("ran twice", twice), ("bad", bad)):
    if v:
        print(f"     {what}: {v}")
sys.exit(0 if ok else 1)
EOF
# Identical to the local run.
if $PY "$REPO/tests/workflow/same_outputs.py" "$W/local" "$W/campaign/out" > "$W/same_outputs.txt"; then
  echo "ok   outputs identical to the local run: $(tail -n 1 "$W/same_outputs.txt")"
else
  head -n 20 "$W/same_outputs.txt"; echo "FAIL outputs differ from the local run"; fail=1
fi
part "checks (jobs, outputs)" "$t"

t=$(now)
pids=$(cat "$W"/cluster/*.pid)
"$REPO/bench/campaign/slurm_cluster.sh" stop "$W/cluster"
trap - EXIT
for p in $pids; do
  if kill -0 "$p" 2>/dev/null; then echo "FAIL daemon $p still running after stop"; fail=1; fi
done
part "cluster stop" "$t"

echo "== $(date -u +%FT%TZ) $(git -C "$REPO" rev-parse --short HEAD); $(snakemake --version | sed 's/^/snakemake /'), $(slurmctld -V)"
echo "== $(nproc) cores; load before/after: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '%s\n' "${PARTS[@]}"
echo "work folder: $W"
[[ $fail -eq 0 ]] && echo "passed" || { echo "FAILED"; exit 1; }

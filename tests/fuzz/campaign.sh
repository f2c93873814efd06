#!/usr/bin/env bash
# A long fuzzing campaign: each harness in turn, at nice 19 (benchmarks may be
# timed on the same machine), from a copy of its corpus, until RUNS executions
# or SECONDS seconds, whichever comes first. Unlike run.sh it does not stop at
# the first crash: libFuzzer's fork mode (-fork=1 -ignore_crashes=1) keeps
# going and every crashing input is saved in OUTDIR/<harness>/ as crash-*.
# Prints one line per harness: executions, seconds, exec/s, crashes; the full
# logs stay in OUTDIR.
#   tests/fuzz/campaign.sh BUILD_DIR OUTDIR [RUNS] [SECONDS] [HARNESS...]
#   tests/fuzz/campaign.sh build/fuzz /tmp/fuzz 1000000 600
# Environment: FUZZ_NICE (default 19), FUZZ_TIMEOUT (seconds per input before
# it counts as a hang, default 10; raise it if the campaign may be paused
# with SIGSTOP while something else is timed, or the pause reads as a hang),
# FUZZ_FORK (parallel child processes of the one run, default 1), FUZZ_RSS_MB
# (memory limit of an input, default 2048; corrupt HDF5 headers ask for 1-17
# GB, and near the limit libhdf5 touches what it gets before refusing: a
# lower limit reports those as OOM at once instead of spending seconds on each).
set -uo pipefail
B=$(cd "$1" && pwd); OUT=$2; RUNS=${3:-1000000}; SECS=${4:-600}; shift 4 2>/dev/null || shift $#
HARNESSES=${*:-csv toml raw_json hdf5 tiff}
SRC=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
export ASAN_OPTIONS="allocator_may_return_null=1:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$SRC/lsan.supp"
for h in $HARNESSES; do
  rm -rf "$OUT/$h" && mkdir -p "$OUT/$h/corpus"
  cp -r "$SRC/corpus/$h/." "$OUT/$h/corpus/"
  t0=$(date +%s.%N)
  # fork mode: one child process runs the inputs, the parent merges coverage
  # and restarts it after a crash; -runs is then the total budget.
  (cd "$OUT/$h" && nice -n "${FUZZ_NICE:-19}" "$B/tests/fuzz/fuzz_$h" -fork="${FUZZ_FORK:-1}" -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
     -runs="$RUNS" -max_total_time="$SECS" -timeout="${FUZZ_TIMEOUT:-10}" -rss_limit_mb="${FUZZ_RSS_MB:-2048}" -malloc_limit_mb="${FUZZ_RSS_MB:-2048}" -max_len=65536 \
     -print_final_stats=1 corpus >"$OUT/$h.log" 2>&1)
  t1=$(date +%s.%N)
  # Fork mode reports cumulative executions in its status lines: "#N: cov: ...".
  execs=$(grep -oE '^#[0-9]+' "$OUT/$h.log" | tail -1 | tr -d '#')
  crashes=$(ls "$OUT/$h"/crash-* 2>/dev/null | wc -l)
  ooms=$(ls "$OUT/$h"/oom-* 2>/dev/null | wc -l)
  timeouts=$(ls "$OUT/$h"/timeout-* 2>/dev/null | wc -l)
  awk -v h="$h" -v n="${execs:-0}" -v a="$t0" -v b="$t1" -v c="$crashes" -v o="$ooms" -v t="$timeouts" \
    'BEGIN { s = b - a; printf "fuzz_%s: %d executions in %.0f s (%.0f exec/s), %d crash, %d oom, %d timeout inputs\n", h, n, s, n / s, c, o, t }' \
    | tee -a "$OUT/summary.txt"
done

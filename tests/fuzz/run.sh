#!/usr/bin/env bash
# Runs every fuzz harness for SECONDS each on its corpus (tests/fuzz/corpus/NAME,
# copied so CI leaves the tree clean); fails on the first crash, whose input
# libFuzzer saves as crash-* in the work folder: add it to tests/fuzz/regressions/.
#   tests/fuzz/run.sh BUILD_DIR SECONDS          explore: random seed, SECONDS per harness (make fuzz)
#   tests/fuzz/run.sh BUILD_DIR ci               reproducible: seed 1 and a fixed number of runs per
#                                                harness (~10 s each here), so CI never depends on timing
#                                                or luck (make test)
set -uo pipefail
B=$(cd "$1" && pwd); SECONDS_EACH=${2:-20}
# hdf5: 0 in CI. Exploring it finds memory errors inside libhdf5 1.10.8 itself
# (tests/fuzz/known/), at random moments, which would make CI flaky without
# saying anything about our code; CI replays its regression inputs only.
declare -A CI_RUNS=([tiff]=5000 [raw_json]=40000 [hdf5]=0 [toml]=50000 [csv]=50000)
SRC=$(cd "$(dirname "$0")" && pwd)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
status=0
# malloc of an absurd size returns NULL, as in a normal run, instead of ASan
# aborting: libhdf5 then reports the corrupt file. Our own code would get
# std::bad_alloc, which escapes the harness and is reported as a finding.
export ASAN_OPTIONS="allocator_may_return_null=1:${ASAN_OPTIONS:-}"
for h in tiff raw_json hdf5 toml csv; do
  mkdir -p "$W/$h"
  cp -r "$SRC/corpus/$h/." "$W/$h/" 2>/dev/null || true
  # Regression inputs first: each must pass as a plain run.
  if compgen -G "$SRC/regressions/$h/*" >/dev/null; then
    LSAN_OPTIONS="suppressions=$SRC/lsan.supp" "$B/tests/fuzz/fuzz_$h" "$SRC"/regressions/$h/* >"$W/$h.regress.log" 2>&1 || { echo "fuzz_$h: regression input fails"; tail -30 "$W/$h.regress.log"; status=1; }
  fi
  if [[ "$SECONDS_EACH" == ci ]]; then
    LIMIT="-seed=1 -runs=${CI_RUNS[$h]}"
    if [[ ${CI_RUNS[$h]} -eq 0 ]]; then echo "fuzz_$h: regression inputs only (see tests/fuzz/known/README.md)"; continue; fi
  else LIMIT="-max_total_time=$SECONDS_EACH"; fi
  (cd "$W" && LSAN_OPTIONS="suppressions=$SRC/lsan.supp" "$B/tests/fuzz/fuzz_$h" $LIMIT \
     -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
     -print_final_stats=1 "$W/$h" >"$W/$h.log" 2>&1) || {
    echo "fuzz_$h: FAILED"; grep -E "ERROR|SUMMARY|crash-|Test unit written" "$W/$h.log" | head -20; tail -5 "$W/$h.log"
    mkdir -p fuzz-findings && cp "$W"/crash-* "$W"/leak-* "$W"/timeout-* "$W"/oom-* fuzz-findings/ 2>/dev/null || true
    status=1; continue; }
  runs=$(grep -m1 "stat::number_of_executed_units" "$W/$h.log" | awk '{print $2}')
  echo "fuzz_$h: ok, $runs executions ($LIMIT)"
done
exit $status

#!/usr/bin/env bash
# Time and peak memory of `tomograin synth --preset zeolite` at 256³ and 512³ with
# 1 and 2 OpenMP threads (packing, render, imaging, truth and write are timed
# separately by the command; peak memory is the process's VmHWM).
# Usage: bench/data_synth/run_render_zeolite.sh [BUILD_DIR] [SIZES...]
set -eu
B=${1:-build/release}
shift || true
SIZES=${*:-256 512}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
for n in $SIZES; do
  for t in 1 2; do
    echo "== zeolite size $n, $t thread(s)"
    OMP_NUM_THREADS=$t TOMOGRAIN_QUIET=1 "$B/tomograin" synth --preset zeolite --size "$n" -o "$T/z.h5"
    rm -f "$T"/z*
  done
done

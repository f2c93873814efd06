#!/usr/bin/env bash
# Runs every benchmark that is built; results go to stdout (and bench/results/ where a bench writes files).
set -u
B=${1:-build/release}
echo "== machine: $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB; load: $(cut -d' ' -f1-3 /proc/loadavg)"
for exe in "$B"/bench/*/*bench*; do
  [[ -x "$exe" ]] || continue
  echo "== $(basename "$exe")"
  "$exe" || echo "(failed: $?)"
done
for s in bench/*/run_*.sh; do
  [[ -x "$s" ]] || continue
  echo "== $s"
  "$s" "$B" || echo "(failed: $?)"
done

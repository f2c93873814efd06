#!/usr/bin/env bash
# Overhead of the breakage machinery on a run where nothing breaks (issue 7):
# the same packing compressed to STRAIN with [breakage] enabled = false, and
# with enabled = true but sigma_t0 = 1e15 Pa (checks every 10 steps, force
# hook installed, no split ever). Prints the oedometer's own wall time of
# each of REPS runs (pluviation excluded: the packing is read from CSV).
# Usage: bench/dem/breakage_overhead.sh TOMOGRAIN_BINARY [STRAIN=0.1] [REPS=3]
set -euo pipefail
BIN=${1:?path to the tomograin binary}
STRAIN=${2:-0.1}
REPS=${3:-3}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
# The demo cell, dem/examples/demo.toml (its [oedometer] table does not enter the packing).
"$BIN" dem pack "$(dirname "$0")/../../dem/examples/demo.toml" -o "$W/packing.csv" >/dev/null
for mode in off on_nothing_breaks; do
  {
    echo "[specimen]"; echo "packing_csv = \"$W/packing.csv\""
    echo "[walls]"; echo "cylinder_radius_m = 4.0e-3"
    echo "[oedometer]"; echo "target_strain = $STRAIN"; echo "snapshot_strains = []"; echo "history_every_steps = 1000"
    echo "[breakage]"
    if [ "$mode" = off ]; then echo "enabled = false"; else echo "enabled = true"; echo "sigma_t0_Pa = 1.0e15"; fi
  } > "$W/$mode.toml"
  for r in $(seq "$REPS"); do
    out=$("$BIN" dem oedometer "$W/$mode.toml" -o "$W/run_${mode}_$r")
    echo "$mode rep $r: $(echo "$out" | grep -o 'wall [0-9.]* s'), $(echo "$out" | grep -o 'top stress [0-9.e+-]* MPa')"
  done
done

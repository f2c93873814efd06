#!/bin/bash
# recover.sh with a crush-test target added (issue 21: lambda identifiable?).
#   recover_crush.sh TOMOGRAIN SEED OUTDIR [RUNS [GRAINS [EXTRA CALIBRATE ARGS...]]]
# Same seeds, draws, cell, target curve and broken fractions as recover.sh;
# the target file gains [crush] bonds_broken = the mean bonds broken over
# GRAINS (default 30) single-grain crush tests (d = 1.2 mm, travel 0.4 d,
# strength seeds 1..GRAINS) with the drawn sigma_t0 and lambda. That mean is
# computed by `dem calibrate` itself (one implementation): a 2-run calibration
# on ranges [p, p (1 + 1e-9)] around the drawn values, read from its runs.csv.
set -euo pipefail
TG=$(realpath "$1"); SEED=$2; OUT=$3; RUNS=${4:-24}; GRAINS=${5:-30}; shift 3; shift || true; shift || true
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
mkdir -p "$OUT"
read -r SIG LAM < <($PY -c "import random; r = random.Random($SEED); print(6e6 + 18e6 * r.random(), 0.8 + 0.8 * r.random())")
echo "seed $SEED: target sigma_t0 $SIG Pa, lambda $LAM"
# 1. the crush target at the drawn parameters
cat > "$OUT/crush_probe.toml" <<T
[crush]
bonds_broken = 1.0
grains = $GRAINS
[parameters]
sigma_t0_Pa = [$SIG, $($PY -c "print($SIG * (1 + 1e-9))")]
bond_radius_multiplier = [$LAM, $($PY -c "print($LAM * (1 + 1e-9))")]
T
rm -rf "$OUT/crush_probe"
nice -n 10 "$TG" dem calibrate "$HERE/small_cell.toml" --target "$OUT/crush_probe.toml" -o "$OUT/crush_probe" \
  --runs 2 --initial 2 --jobs 2 --no-plot > "$OUT/crush_probe.log"
B=$($PY -c "import csv; r = list(csv.DictReader(open('$OUT/crush_probe/runs.csv'))); print(r[0]['crush_bonds_broken'], r[1]['crush_bonds_broken'])")
echo "crush target: mean bonds broken over $GRAINS grains: $B (the probe's two runs)"
B=${B%% *}
# 2. the oedometer target and the calibration: recover.sh, its target file
#    with this crush target appended (EXTRA_TARGET)
printf '[crush]\nbonds_broken = %s\ngrains = %s\n' "$B" "$GRAINS" > "$OUT/crush_target.toml"
EXTRA_TARGET="$OUT/crush_target.toml" "$HERE/recover.sh" "$TG" "$SEED" "$OUT" "$RUNS" "$@"

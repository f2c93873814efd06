#!/bin/bash
# Does `tomograin dem calibrate` recover known parameters? (issue 21)
#   recover.sh TOMOGRAIN SEED OUTDIR [RUNS [EXTRA CALIBRATE ARGS...]]
# 1. draws sigma_t0 and lambda uniformly within the default ranges
#    ([6, 24] MPa, [0.8, 1.6]) from SEED (Python's random.Random(SEED));
# 2. runs the small cell (small_cell.toml, 126 grains, to 8 % strain) with
#    them: the target is that run's stress-strain curve (history.csv) and its
#    broken fraction at 4, 6 and 8 % strain (plus the file EXTRA_TARGET's
#    text when set: recover_crush.sh's crush target);
# 3. calibrates from the default ranges with design seed SEED + 100 (a
#    different starting design), RUNS runs (default 24), 2 at a time;
# 4. prints the relative error of the best run's and of the surrogate's
#    optimum parameters against the drawn ones.
set -euo pipefail
TG=$(realpath "$1"); SEED=$2; OUT=$3; RUNS=${4:-24}; shift 3; shift || true
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
mkdir -p "$OUT"
read -r SIG LAM < <($PY -c "import random; r = random.Random($SEED); print(6e6 + 18e6 * r.random(), 0.8 + 0.8 * r.random())")
echo "seed $SEED: target sigma_t0 $SIG Pa, lambda $LAM"
sed "s|\"../../../tests|\"$(cd "$HERE/../../.." && pwd)/tests|" "$HERE/small_cell.toml" > "$OUT/target_config.toml"
printf 'sigma_t0_Pa = %s\nbond_radius_multiplier = %s\n' "$SIG" "$LAM" >> "$OUT/target_config.toml"
rm -rf "$OUT/target_run" "$OUT/calib"
OMP_NUM_THREADS=1 TOMOGRAIN_QUIET=1 nice -n 10 "$TG" dem oedometer "$OUT/target_config.toml" -o "$OUT/target_run" | tail -2
$PY - "$OUT" <<'PYEOF'
import csv, sys
import numpy as np
out = sys.argv[1]
h = list(csv.DictReader(open(f"{out}/target_run/history.csv")))
e = np.array([float(r["strain"]) for r in h]); g = np.array([float(r["grains_broken"]) for r in h])
n0 = sum(1 for _ in open(f"{out}/target_run/packing_initial.csv")) - 1
s = [0.04, 0.06, 0.08]
f = [float(np.interp(x, e, g)) / n0 for x in s]
with open(f"{out}/target.toml", "w") as t:
    t.write('[target]\nstress_strain_csv = "target_run/history.csv"\n'
            f"broken_strain = {s}\nbroken_fraction = {f}\n")
print("broken fraction at 4/6/8 %:", " ".join(f"{x:.3f}" for x in f))
PYEOF
if [ -n "${EXTRA_TARGET:-}" ]; then cat "$EXTRA_TARGET" >> "$OUT/target.toml"; fi
nice -n 10 "$TG" dem calibrate "$HERE/small_cell.toml" --target "$OUT/target.toml" -o "$OUT/calib" \
  --runs "$RUNS" --initial 10 --batch 2 --jobs 2 --seed $((SEED + 100)) "$@"
$PY - "$OUT" "$SIG" "$LAM" <<'PYEOF'
import json, sys
out, sig, lam = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
c = json.load(open(f"{out}/calib/calibration.json"))
for what, p in (("best run " + c["best"]["run"], c["best"]["parameters"]), ("surrogate optimum", c["surrogate"]["predicted_optimum"])):
    print(f"{what}: sigma_t0 {p[0]/1e6:.3f} MPa ({100*(p[0]/sig-1):+.1f} %), lambda {p[1]:.4f} ({100*(p[1]/lam-1):+.1f} %)")
PYEOF

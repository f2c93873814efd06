#!/usr/bin/env bash
# `tomograin analyse` end to end on a synthetic scan with known truth: every
# true grain found once, and the D50 of the measured grading (by mass on Dmed)
# within 3 % of the truth table's, computed independently here with numpy.
set -eu
TG=$1
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
"$TG" synth --preset spheres --seed 3 -o s.h5 >/dev/null
"$TG" analyse s.h5 -o res --grain-diameter-um 400 >/dev/null
test -f res/labels.h5 -a -f res/particles.csv -a -f res/psd.csv -a -f res/psd_summary.csv
# A failing analysis leaves no results folder.
if "$TG" analyse missing.h5 -o bad 2>/dev/null; then echo "FAIL: missing input accepted"; exit 1; fi
test ! -e bad || { echo "FAIL: partial results folder left behind"; exit 1; }
/usr/bin/python3 - <<'PY'
import csv, numpy as np
truth = list(csv.DictReader(open("s_truth.csv")))
parts = list(csv.DictReader(open("res/particles.csv")))
summ = list(csv.DictReader(open("res/psd_summary.csv")))[0]
full = [t for t in truth if t.get("cropped", "0") in ("0", "0.0", "false")]
def d50(d, w):
    o = np.argsort(d); d = np.asarray(d)[o]; c = np.cumsum(np.asarray(w)[o]); c /= c[-1]
    return float(np.interp(0.5, c, d))
# Truth: grains by volume on their (exact) Dmed; all grains, cropped ones included, as the scan holds them.
vt = [float(t["volume_mm3"]) for t in truth]; dt = [float(t["dmed_mm"]) for t in truth]
ref = d50(dt, vt); got = float(summ["d50_mm"])
print(f"particles {len(parts)} (truth {len(truth)}), D50 {got:.4f} mm vs truth {ref:.4f} mm")
assert abs(len(parts) - len(truth)) <= 0.02 * len(truth), "particle count off by more than 2 %"
# Measured bias: -1.7 % with FIFO ties in the watershed, -2.4 % with slice-ordered
# rounds (same labelled volume within 0.1 %: Feret boxes of 8-voxel-radius grains
# move by a voxel); 3 % still catches a chain that loses or swaps particles.
assert abs(got - ref) <= 0.03 * ref, "D50 off by more than 3 %"
assert summ["file"] == "res/particles.csv", f"summary names {summ['file']!r}, not the results folder's particles.csv"
PY
echo "1 passed, 0 failed"

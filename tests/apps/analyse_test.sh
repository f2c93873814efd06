#!/usr/bin/env bash
# `tomograin analyse` end to end on a synthetic scan with known truth:
#  * every true grain found once: each true label of s.h5's /labels (grains
#    of at least 155 voxels) matched by one result label with IoU >= 0.5,
#    and no result label matching two grains (counted here with numpy);
#  * the D50 of the measured grading (by mass on Dmed) against two
#    references computed here, which split the error in two: (a) the same
#    measurement on the *true* labels (`tomograin measure s.h5`): the
#    segmentation's share; (b) the truth table's exact Dmed: the whole chain.
#    Measured (seed 3): -4.35 % against (a) (the labels lose their boundary
#    and watershed-line voxels: grains 8 voxels in radius read smaller),
#    +1.5 % from (a) to (b) (Feret calipers of digitised grains), -2.91 %
#    in all: the two partly cancel, so (b)'s 3 % bound has a thin margin
#    (0.09 %) and the test asserts each share on its own. Since analyse
#    weighs by the grey-level volume (measure --grey, grey_volume.hpp):
#    -3.30 % against (a), -1.84 % in all (Dmed itself is the label's).
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
"$TG" measure s.h5 -o truth_particles.csv >/dev/null
/usr/bin/python3 - <<'PY'
import csv, h5py, numpy as np
truth = list(csv.DictReader(open("s_truth.csv")))
parts = list(csv.DictReader(open("res/particles.csv")))
tparts = list(csv.DictReader(open("truth_particles.csv")))
summ = list(csv.DictReader(open("res/psd_summary.csv")))[0]
def d50(d, w):
    o = np.argsort(d); d = np.asarray(d)[o]; c = np.cumsum(np.asarray(w)[o]); c /= c[-1]
    return float(np.interp(0.5, c, d))

# Every true grain found once (IoU >= 0.5 with one result label, and that
# label with no other grain); grains under 155 voxels (slivers cut by the
# crop) are not counted, as in segmentation's accuracy test.
with h5py.File("s.h5", "r") as f:
    t = f["/labels"][()].ravel().astype(np.int64)
with h5py.File("res/labels.h5", "r") as f:
    r = f["/labels"][()].ravel().astype(np.int64)
assert t.shape == r.shape, "label volumes differ in shape"
nt, nr = int(t.max()) + 1, int(r.max()) + 1
both = (t > 0) & (r > 0)
pair, inter = np.unique(t[both] * nr + r[both], return_counts=True)
st, sr = np.bincount(t, minlength=nt), np.bincount(r, minlength=nr)
ti, ri = pair // nr, pair % nr
iou = inter / (st[ti] + sr[ri] - inter)
good = iou >= 0.5
counted = [g for g in range(1, nt) if st[g] >= 155]
matched = set(ti[good])
lost = [g for g in counted if g not in matched]
used = np.bincount(ri[good], minlength=nr)
print(f"true grains {len(counted)}, result labels {nr - 1}, lost {len(lost)}, labels matching two grains {int((used > 1).sum())}")
assert not lost, f"true grains not found: {lost[:10]}"
assert (used <= 1).all(), "a result label covers two true grains"

# D50 (by mass on Dmed). (a) Same measurement on the true labels: the
# segmentation's share. (b) The truth table's exact Dmed, all grains (cropped
# ones included, as the scan holds them): the whole chain.
got = float(summ["d50_mm"])
ref_seg = d50([float(p["d_med_mm"]) for p in tparts], [float(p["volume_mm3"]) for p in tparts])
ref = d50([float(x["dmed_mm"]) for x in truth], [float(x["volume_mm3"]) for x in truth])
print(f"D50 {got:.4f} mm; measured on the true labels {ref_seg:.4f} mm ({got / ref_seg - 1:+.2%}); "
      f"truth {ref:.4f} mm ({got / ref - 1:+.2%})")
# (a) one-sided and bounded: the labels can only read grains smaller than
# the true labels do (measured -4.35 %); 6 % is that measurement plus
# margin, not derived.
assert 0.94 * ref_seg <= got <= ref_seg, "segmentation moves D50 outside [-6 %, 0] of the true labels' D50"
assert 1.0 <= ref_seg / ref <= 1.03, "the measurement of the true labels is off the truth by more than [0, +3 %]"
# The whole chain (issue 9's bound; -1.7 % with FIFO ties in the watershed,
# -2.4 % with slice-ordered rounds, -2.91 % now): a chain that loses, merges
# or swaps particles fails the found-once check above first.
assert abs(got - ref) <= 0.03 * ref, "D50 off by more than 3 %"
assert summ["file"] == "res/particles.csv", f"summary names {summ['file']!r}, not the results folder's particles.csv"
PY
# analyse.json: each step's time and own peak memory, per voxel of the scan.
/usr/bin/python3 - <<'PY'
import json, h5py
j = json.load(open("res/analyse.json"))
with h5py.File("s.h5", "r") as f:
    n = f["/labels"].size
assert j["voxels"] == n, (j["voxels"], n)
assert [s["name"] for s in j["stages"]] == ["segment", "measure", "psd"], j["stages"]
for s in j["stages"]:
    assert s["seconds"] >= 0 and s["peak_rss_bytes"] > 0, s
    assert abs(s["peak_rss_bytes_per_voxel"] * n - s["peak_rss_bytes"]) < 1, s
assert j["peak_rss_bytes"] == max(s["peak_rss_bytes"] for s in j["stages"])
assert abs(j["seconds_total"] - sum(s["seconds"] for s in j["stages"])) < 1e-9
PY
echo "1 passed, 0 failed"

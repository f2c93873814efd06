#!/usr/bin/env bash
# `analyse --memory-limit` (issue 23): a scan over the limit is segmented
# and measured slab by slab (segmentation/segment_chunked.hpp,
# measure/measure_chunked.hpp) with the labels and particle table of the
# whole-volume run: every voxel and every cell equal, the coordination
# column too (contacts in two passes over slabs). The scan is the 128^3
# synthetic one at 25 um (grains of radius 8 voxels) stacked on its mirror
# image, 256 x 128 x 128: segment's estimate is 160 MiB in one piece (8
# B/voxel with the split repair's grey code + 128 MiB), a slab of 16 core and
# 2 x 48 margin slices 142 MiB, measure's 156 MiB in one piece, so 147 MiB
# forces slabs for both steps (a 128^3 scan cannot do both: a slab of 112
# slices costs segment more than the whole scan costs measure). Then
# measure's refusals: a limit too small for one slab, an .h5 table (exit 2,
# nothing written). The same slab runs from a multi-page TIFF. ~25 s.
set -eu
TG=$1
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
"$TG" synth --preset spheres --seed 3 -o s.h5 >/dev/null
/usr/bin/python3 - <<'PY'
import h5py, numpy as np
with h5py.File("s.h5", "r") as f, h5py.File("tall.h5", "w") as g:
    v = f["volume"][()]
    d = g.create_dataset("volume", data=np.concatenate([v, v[::-1]], axis=0))
    for k, a in f["volume"].attrs.items():
        d.attrs[k] = a
    for k in ("voxel_size_m", "origin_m"):
        g.attrs[k] = f.attrs[k]
PY
"$TG" analyse tall.h5 -o whole --grain-diameter-um 400 >/dev/null
"$TG" analyse tall.h5 -o slabs --grain-diameter-um 400 --memory-limit 147MiB > slabs.log
grep -q "^segmenting tall.h5 .* slab by slab" slabs.log || { echo "FAIL: segment did not go by slabs"; cat slabs.log; exit 1; }
grep -q "^measuring .* slab by slab" slabs.log || { echo "FAIL: measure did not go by slabs"; cat slabs.log; exit 1; }
# measure alone on the whole run's labels, its grey volumes from the scan, in slabs
"$TG" measure whole/labels.h5 --grey tall.h5 --memory-limit 140MiB -o m.csv > m.log
grep -q "slab by slab" m.log || { echo "FAIL: measure 140MiB did not go by slabs"; cat m.log; exit 1; }
/usr/bin/python3 - <<'PY'
import csv, h5py, numpy as np
with h5py.File("whole/labels.h5", "r") as f:
    a = f["/labels"][()]
with h5py.File("slabs/labels.h5", "r") as f:
    b = f["/labels"][()]
assert a.shape == b.shape and (a == b).all(), f"labels differ in {(a != b).sum()} voxels"
ref = list(csv.DictReader(open("whole/particles.csv")))
for name in ("slabs/particles.csv", "m.csv"):
    got = list(csv.DictReader(open(name)))
    assert len(got) == len(ref) > 20, (name, len(got), len(ref))
    cols = list(ref[0].keys())
    assert "coordination" in cols and cols == list(got[0].keys()), (name, cols, list(got[0].keys()))
    bad = [(c, r["label"]) for r, g in zip(ref, got) for c in cols if r[c] != g[c]]
    assert not bad, f"{name}: {len(bad)} cells differ, e.g. {bad[:5]}"
for f in ("psd.csv", "psd_summary.csv"):  # they name their input: whole/ or slabs/particles.csv
    assert open("whole/" + f).read() == open("slabs/" + f).read().replace("slabs/", "whole/"), f
print(f"labels identical ({a.size} voxels), {len(ref)} particles: every cell equal in both slab runs")
PY
# The same from a multi-page TIFF of the scan (each slab's pages read alone, segment and
# measure): the labels and table of that TIFF analysed in one piece.
"$TG" convert tall.h5 -o tall.tif >/dev/null
"$TG" analyse tall.tif -o twhole --grain-diameter-um 400 >/dev/null
"$TG" analyse tall.tif -o tslabs --grain-diameter-um 400 --memory-limit 147MiB > tslabs.log
grep -q "^segmenting tall.tif .* slab by slab" tslabs.log || { echo "FAIL: TIFF segment did not go by slabs"; cat tslabs.log; exit 1; }
grep -q "^measuring .* slab by slab" tslabs.log || { echo "FAIL: TIFF measure did not go by slabs"; cat tslabs.log; exit 1; }
/usr/bin/python3 - <<'PY'
import h5py
with h5py.File("twhole/labels.h5", "r") as f, h5py.File("tslabs/labels.h5", "r") as g:
    a, b = f["/labels"][()], g["/labels"][()]
assert a.shape == b.shape and (a == b).all(), f"TIFF: labels differ in {(a != b).sum()} voxels"
ra, rb = open("twhole/particles.csv").read().splitlines(), open("tslabs/particles.csv").read().splitlines()
assert len(ra) > 20 and ra == rb, f"TIFF: particle tables differ ({len(ra)} / {len(rb)} lines)"
print(f"TIFF by slabs: labels and {len(ra) - 1} particles as in one piece")
PY
# Refusals: exit 2, one line, nothing written.
set +e
"$TG" measure whole/labels.h5 --memory-limit 20MiB -o tiny.csv 2> tiny.err; rc=$?
set -e
[ "$rc" = 2 ] || { echo "FAIL: a limit too small for one slab gave exit $rc"; exit 1; }
grep -q "too small to measure" tiny.err || { echo "FAIL: unclear message: $(cat tiny.err)"; exit 1; }
test ! -e tiny.csv || { echo "FAIL: tiny.csv written"; exit 1; }
set +e
"$TG" measure whole/labels.h5 --memory-limit 135MiB -o t.h5 2> h5.err; rc=$?
set -e
[ "$rc" = 2 ] && grep -q "csv table only" h5.err && test ! -e t.h5 || { echo "FAIL: .h5 output by slabs: exit $rc, $(cat h5.err)"; exit 1; }
echo "slab runs OK"

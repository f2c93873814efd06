#!/usr/bin/env bash
# Issue 23, volumes larger than memory: a 2048^3 scan (the 512^3 zeolite
# scan mirror-tiled 4 x 4 x 4: 64 x 932 grains, 16 GiB of uint16) segmented
# and measured slab by slab under --memory-limit, and the 512^3 scan's table
# measured in one piece and in slabs (identical CSVs).
#
#   bench/scale/big_slabs.sh [BUILD] [WORK] [LIMIT]     (LIMIT default 12GiB)
#
# Needs ~20 GB of disk in WORK and LIMIT + ~1 GB of memory.
set -eu
B=${1:-build/release}
W=${2:-/work/big}
LIMIT=${3:-12GiB}
T=$(realpath "$B/apps/tomograin")
HERE=$(dirname "$(realpath "$0")")
mkdir -p "$W"
cd "$W"
export TOMOGRAIN_QUIET=1
tv() { /usr/bin/time -v "$@"; }
echo "== $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores, commit $(git -C "$HERE" rev-parse --short HEAD)"
[ -f z512.h5 ] || tv "$T" synth --preset zeolite --size 512 -o z512.h5 > synth512.log 2> synth512.time
[ -f l512.h5 ] || "$T" segment z512.h5 -o l512.h5 > seg512.log
for lim in none 300MiB; do
  a=(); [ $lim = none ] || a=(--memory-limit $lim)
  tv "$T" measure l512.h5 --grey z512.h5 --no-contacts "${a[@]}" -o m512_$lim.csv > m512_$lim.log 2> m512_$lim.time
done
cmp m512_none.csv m512_300MiB.csv && echo "512^3: one piece and slabs give identical tables"
[ -f z2048.h5 ] || tv /usr/bin/python3 "$HERE/tile_scan.py" z512.h5 4 z2048.h5 > tile.log 2> tile.time
echo "== segment 2048^3 under $LIMIT: $(date -u +%T)"
tv "$T" segment z2048.h5 -o l2048.h5 --memory-limit "$LIMIT" > seg2048.log 2> seg2048.time
grep -E "labels|pass 1|peak" seg2048.log
grep -E "Elapsed|Maximum|Percent" seg2048.time
echo "== measure 2048^3 under $LIMIT: $(date -u +%T)"
tv "$T" measure l2048.h5 --grey z2048.h5 --memory-limit "$LIMIT" -o m2048.csv > m2048.log 2> m2048.time
grep -E "slab|particles|peak" m2048.log
grep -E "Elapsed|Maximum|Percent" m2048.time
/usr/bin/python3 - <<'PY'
# The copy at the origin against the 512^3 one-piece table (the other copies'
# labels differ a little: the flood's tie order depends on the whole slices,
# bench/scale/RESULTS.md), every column but the position columns.
import csv
import h5py
import numpy as np
a = list(csv.DictReader(open("m512_none.csv")))
b = list(csv.DictReader(open("m2048.csv")))
print(f"2048^3: {len(b)} particles (64 x {len(a)} = {64 * len(a)})")
org = h5py.File("l512.h5", "r")["labels"].attrs["origin_m"] * 1e3
edge = 512 * h5py.File("l512.h5", "r")["labels"].attrs["voxel_size_m"][0] * 1e3
pos = lambda r: np.array([float(r["cz_mm"]), float(r["cy_mm"]), float(r["cx_mm"])]) - org
ca = np.array([pos(r) for r in a])
cols = [c for c in a[0] if c in b[0] and c not in ("label", "cz_mm", "cy_mm", "cx_mm") and not c.startswith("bbox")]
same = n = 0
for r in b:
    c = pos(r)
    if (c >= edge).any():
        continue
    n += 1
    m = a[int(np.argmin(np.abs(ca - c).max(1)))]
    same += all(m[x] == r[x] for x in cols)
print(f"copy at the origin: {same} of {n} rows equal to the 512^3 table in every column")
PY
echo "== done $(date -u +%T)"

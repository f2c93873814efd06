#!/usr/bin/env bash
# Issue 23, side by side at the study's voxel size: tomograin segment and the
# scikit-image/scipy peer (/work/shared/peers/skimage/ref_pipeline.py) on the
# largest crop of the study's specimen the peer can hold here (~55 B/voxel),
# and both projected to the full 1220^3 scan (time and memory linear in the
# voxel count: both pipelines are O(N)).
#
#   bench/scale/skimage_crop.sh [BUILD] [WORK] [SIZE]      (SIZE default 640)
#
# The crop: `synth --preset zeolite --size SIZE --voxel-um 12.3` (the study's
# voxel size; grains of radius 680 / 12.3 = 55.3 voxels, as in the full scan).
set -eu
B=${1:-build/release}
W=${2:-/work/crop}
N=${3:-640}
T=$(realpath "$B/apps/tomograin")
REF=/work/shared/peers/skimage/ref_pipeline.py
mkdir -p "$W"
cd "$W"
export TOMOGRAIN_QUIET=1
echo "== $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores"
[ -f z$N.h5 ] || "$T" synth --preset zeolite --size "$N" --voxel-um 12.3 -o z$N.h5 > synth.log
/usr/bin/time -v "$T" segment z$N.h5 -o tg.h5 > tg.log 2> tg.time
[ -f z$N.json ] || "$T" convert z$N.h5 -o z$N.json > /dev/null
/usr/bin/time -v /usr/bin/python3 "$REF" z$N.json --out ref --radius 55.285 > ref.log 2> ref.time
echo "== $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg)"
/usr/bin/python3 - "$N" <<'PY'
import json, re, sys
n = int(sys.argv[1]); vox = n ** 3; full = 1220 ** 3
def gnu(path):
    t = open(path).read()
    wall = t.split("Elapsed (wall clock) time (h:mm:ss or m:ss): ")[1].split("\n")[0].split(":")
    w = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall)))
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) * 1024
    cpu = re.search(r"Percent of CPU this job got: (\d+)%", t).group(1)
    return w, rss, cpu
tg = json.load(open("tg.segment.json"))
ref = json.load(open("ref_timing.json"))
st = {r["stage"]: r for r in ref["stages"]}
ref_seg = sum(st[k]["seconds"] for k in ("threshold", "binarise", "fill_pores", "edt", "markers", "watershed", "relabel"))
tw, trss, tcpu = gnu("tg.time")
rw, rrss, rcpu = gnu("ref.time")
print(f"crop {n}^3 ({vox / 1e6:.0f} M voxels), projection x{full / vox:.2f} to 1220^3")
print("| pipeline | segmentation s | whole command wall s (CPU) | peak RSS | B/voxel | labels | projected segmentation s at 1220^3 | projected peak at 1220^3 |")
print("|---|---|---|---|---|---|---|---|")
print(f"| tomograin segment | {tg['seconds_total']:.1f} | {tw:.1f} ({tcpu} %) | {trss / 2**30:.2f} GiB | {trss / vox:.2f} | {tg['labels']['count']} | {tg['seconds_total'] * full / vox:.0f} | {trss / vox * full / 2**30:.1f} GiB |")
print(f"| skimage peer | {ref_seg:.1f} | {rw:.1f} ({rcpu} %) | {rrss / 2**30:.2f} GiB | {rrss / vox:.2f} | {ref.get('labels', '?')} | {ref_seg * full / vox:.0f} | {rrss / vox * full / 2**30:.1f} GiB |")
print(f"ratio (segmentation): {ref_seg / tg['seconds_total']:.1f}x")
PY

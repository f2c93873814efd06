#!/usr/bin/env bash
# bench/scale: the study's full-size image chain on one machine (issue #23).
#   1. `tomograin synth --preset zeolite --size 1220`: a 1220^3 scan at 12.3 um
#      (932 grains; ~17 GiB peak, 12 GB file with its truth labels);
#   2. `tomograin analyse` on it (segment + measure + psd; DIR/analyse.json
#      has each step's wall time and peak memory, bytes per voxel);
#   3. `tomograin track` of five label stages made from analyse's labels by
#      compressing the specimen along z by the study's strains
#      (compress_stages.py: grains flatten, which real ones do not; the
#      stages cost the tracker what real ones would: same size, same count);
#   4. with a DEM run folder as third argument (`tomograin dem oedometer` to
#      15.48 %), `tomograin compare` of the five stages against the run: each
#      stage segmented, measured and tracked, the matching DEM snapshot
#      voxelised, imaged, segmented and measured at the scan's 12.3 um
#      (~1.4e9 voxels) and tracked, and the DEM's exact lineage (report.json
#      gives each stage's peak bytes per voxel).
# Run it alone on the machine: it needs ~17 GiB of memory (synth) and ~14 GB of disk.
#
#   bench/scale/full_size.sh BUILD WORK [DEMRUN]
#   bench/scale/full_size.sh build/release /work/big runs/calibrated
set -eu
B=${1:-build/release}
W=${2:-/tmp/tomograin_full_size}
T=$(realpath "$B/apps/tomograin")
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$W/stages"
cd "$W"
export TOMOGRAIN_QUIET=1
echo "== $(date -u +%FT%TZ), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg), commit $(git -C "$HERE" rev-parse --short HEAD)"
[[ -f z1220.h5 ]] || /usr/bin/time -v "$T" synth --preset zeolite --size 1220 -o z1220.h5 > synth.log 2>&1
grep -E "Elapsed|Maximum resident|Percent" synth.log || true
rm -rf analysed
/usr/bin/time -v "$T" analyse z1220.h5 -o analysed --voxel-um 12.3 > analyse.log 2>&1
grep -E "Elapsed|Maximum resident|Percent" analyse.log
cat analysed/analyse.json
/usr/bin/python3 "$HERE/compress_stages.py" analysed/labels.h5 stages > stages.log
rm -rf tracked
/usr/bin/time -v "$T" track stages/L0.h5 stages/L1.h5 stages/L2.h5 stages/L3.h5 stages/L4.h5 -o tracked > track.log 2>&1
grep -E "Elapsed|Maximum resident|Percent" track.log
cat tracked/track.json
if [[ -n "${3:-}" ]]; then
  rm -rf compared
  /usr/bin/time -v "$T" compare --xct stages/L0.h5 stages/L1.h5 stages/L2.h5 stages/L3.h5 stages/L4.h5 \
    --xct-strains 0 0.044 0.0712 0.1128 0.1548 --voxel-um 12.3 --dem "$(realpath "$3")" -o compared --no-plots > compare.log 2>&1
  grep -E "Elapsed|Maximum resident|Percent" compare.log
fi

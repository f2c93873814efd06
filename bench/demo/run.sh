#!/usr/bin/env bash
# The demo study of issue 24 by CLI calls, each part timed: the synthetic XCT
# (examples/demo_scene.toml, 30 µm), the DEM oedometer of dem/examples/demo.toml
# (Ø8 mm cell, sequential breakage as in the study), and compare at the scans'
# voxel size. Then, outside the timed demo, what the imaged DEM path keeps of
# the ideal one: counts above the detection limit per stage (count_ratio.py)
# and one-to-one matches on the final snapshot (voxelise + segment + match.py).
# Figures: bench/demo/RESULTS.md.
# Usage: bench/demo/run.sh TOMOGRAIN_BINARY [OUT=out/demo-bench] [THREADS=2]
# Times (wall, user, system, peak memory) go to OUT/times.txt; on a shared
# machine run it under `nice -n 19`.
set -euo pipefail
BIN=$(realpath "${1:?path to the tomograin binary}")
OUT=${2:-out/demo-bench}
THREADS=${3:-2}
HERE=$(cd "$(dirname "$0")" && pwd)
SIZE=280    # 8.4 mm field (examples/demo_scene.toml) / 280 voxels
VOX_UM=30   # = the scans' voxel size, which compare uses for the DEM
# libgomp's default wait policy (spin a while, then sleep): OMP_WAIT_POLICY=passive,
# used here before session 47, puts a thread to sleep at every barrier of a DEM
# step (2 threads: 2.4x the default's wall time on the full specimen's first 9 %).
export OMP_NUM_THREADS=$THREADS TOMOGRAIN_QUIET=1
if [ -e "$OUT" ]; then echo "run.sh: $OUT exists; give a new folder" >&2; exit 2; fi
mkdir -p "$OUT/xct"
TIMES="$OUT/times.txt"

timed() {  # timed NAME COMMAND...: runs it, appends its times to $TIMES
  local name=$1
  shift
  /usr/bin/time -o "$OUT/$name.time" -f "%e %U %S %M" "$@" > "$OUT/$name.log" 2>&1 ||
    { echo "run.sh: $name failed (exit $?), see $OUT/$name.log" >&2; exit 1; }
  read -r wall user sys peak < "$OUT/$name.time"
  echo "$name ($THREADS threads): $wall s wall, $user s user, $sys s system, $peak KiB peak" | tee -a "$TIMES"
}

timed synth "$BIN" synth --preset zeolite-stages --scene "$HERE/../../examples/demo_scene.toml" --size "$SIZE" --seed 1 -o "$OUT/xct/xct.h5"
timed dem "$BIN" dem oedometer "$HERE/../../dem/examples/demo.toml" -o "$OUT/dem"
timed compare "$BIN" compare --xct "$OUT"/xct/xct_stage{0,1,2,3,4}.h5 --dem "$OUT/dem" --synthetic \
  --title "tomograin demo study (bench/demo/run.sh)" -o "$OUT/report"
cat "$OUT"/{synth,dem,compare}.time |
  awk '{w += $1; c += $2 + $3} END {printf "demo total: %.1f s wall, %.1f s CPU (user + system)\n", w, c}' | tee -a "$TIMES"

# What the DEM did (the last history row).
/usr/bin/python3 - "$OUT/dem/history.csv" <<'EOF'
import csv, sys
last = list(csv.DictReader(open(sys.argv[1])))[-1]
print("dem: strain {:.4f}, top stress {:.3f} MPa, grains broken {}, splits by generation {}/{}/{}/{}, spheres {}, "
      "particles {}, fines removed {}, added mass fraction {:.2e}, final dt {} s".format(
          float(last["strain"]), float(last["top_stress_Pa"]) / 1e6, last["grains_broken"], last["splits_gen0"],
          last["splits_gen1"], last["splits_gen2"], last["splits_gen3"], last["spheres"], last["particles"],
          last["fines_removed"], float(last["added_mass_fraction"]), last["time_step_s"]))
EOF
/usr/bin/python3 "$HERE/count_ratio.py" "$OUT/report"

# One to one on the final snapshot, with compare's segmentation scale (median
# grain radius of the first snapshot) and grey levels estimated from the scan.
LAST=$(tail -n 1 "$OUT/dem/snapshots.csv" | cut -d, -f1)
R_VOX=$(/usr/bin/python3 -c "import h5py, numpy as np, sys
f = h5py.File(sys.argv[1]); print(np.median(f['/spheres/r_m'][...]) / ($VOX_UM * 1e-6))" "$OUT/dem/snapshots/strain_00.00pct.h5")
"$BIN" voxelise "$OUT/dem/$LAST" -o "$OUT/final_voxelised.h5" --voxel-um "$VOX_UM" --like "$OUT/xct/xct_stage4.h5" \
  --truth-table > /dev/null
"$BIN" segment "$OUT/final_voxelised.h5" -o "$OUT/final_segmented.h5" --grain-radius-vox "$R_VOX" > /dev/null
/usr/bin/python3 "$HERE/match.py" "$OUT/final_voxelised.h5" "$OUT/final_segmented.h5"

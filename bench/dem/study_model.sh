#!/usr/bin/env bash
# The breakage model's choices and its calibration on the full specimen
# (issue 21): the figures of bench/dem/RESULTS.md, "The study's oedometer:
# model chosen and calibrated".
#
#   bench/dem/study_model.sh TOMOGRAIN OUTDIR [table|calibrate|check|shapes]
#
# table:     the experiment table: each modelling choice as config keys on
#            top of the shipped dem/examples/oedometer.toml (Table 1), on the
#            910-grain pressed specimen, to 15.48 % strain; two runs at a time,
#            one thread each (breakage_options.py full).
# calibrate: `tomograin dem calibrate` of sigma_t0 and lambda for the chosen
#            model against the study's published figures
#            (calibration/study_target.toml), 12 runs, two at a time.
# check:     dem/examples/oedometer_calibrated.toml itself on 1 and 2 threads
#            (same bits; wall times).
# shapes:    FR and AR classes of check's run at 15.48 %, imaged at 24.6 um
#            (`compare`'s dem_ideal series, particles >= 0.2 mm) and of every
#            particle from its spheres (dem_exact, the study's DEM count). compare needs an
#            XCT stage: a synthetic sphere scan stands in for it and its rows are
#            not read (no DEM-only shape command yet).
# Without a step: all four. Long: each run takes 3-8 min of one core.
# JOBS (default 2): runs of the table at a time.
set -euo pipefail
BIN=$(realpath "${1:?path to the tomograin binary}")
export TOMOGRAIN="$BIN"  # breakage_analysis.py asks it for the yield
OUT=${2:?output folder}
STEP=${3:-all}
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
export OMP_WAIT_POLICY=passive TOMOGRAIN_QUIET=1
PACK="$OUT/pack910.csv"
# The study's specimen: pluviation with the shipped config's keys (910
# grains, pressed to 12.25 mm, released: 12.22 mm, 44.32 %).
[ -f "$PACK" ] || "$BIN" dem pack "$ROOT/dem/examples/oedometer.toml" -o "$PACK"

# The speed knobs every row shares (dem/breakage/README.md, "The model
# chosen"): the smallest time step 5e-8 s (the study: 1e-8..1e-7 s) and a
# 0.1 mm Verlet skin (same bits as 0.2 mm, fewer listed pairs).
FAST="breakage.min_time_step_s=5e-8,run.neighbour_skin_m=1.0e-4"
if [ "$STEP" = all ] || [ "$STEP" = table ]; then
  python3 "$HERE/breakage_options.py" full "-j${JOBS:-2}" "$BIN" "$OUT/table" "$PACK" \
    "baseline,$FAST" "walls0,$FAST" "walls0_cyl,$FAST" "walls0+total0.7,$FAST" \
    "study,$FAST" "study,breakage.min_time_step_s=1e-8" "study,breakage.min_time_step_s=2e-8,run.neighbour_skin_m=1.0e-4" \
    "study,breakage.min_time_step_s=1e-7,run.neighbour_skin_m=1.0e-4" \
    "study,$FAST,breakage.check_every_steps=1" "study,$FAST,breakage.check_every_steps=100" \
    "study,$FAST,breakage.bond_damping=0.5" "study,$FAST,breakage.bond_radius_rule=\"min\"" \
    "study,$FAST,breakage.split_bonded=true" "study,$FAST,breakage.sublimit_policy=\"remove\"" \
    "study,$FAST,breakage.bond_radius_multiplier=1.0" "study,$FAST,breakage.bond_radius_multiplier=1.6" \
    "study,$FAST,breakage.bond_normal_strength_Pa=6.6e6,breakage.bond_shear_strength_Pa=6.6e6"
fi
if [ "$STEP" = all ] || [ "$STEP" = calibrate ]; then
  python3 "$HERE/breakage_options.py" config full "$PACK" "study,$FAST" > "$OUT/study_fast.toml"
  [ -d "$OUT/calibration" ] || "$BIN" dem calibrate "$OUT/study_fast.toml" --target "$HERE/calibration/study_target.toml" \
    -o "$OUT/calibration" --runs 12 --initial 6 --batch 2 --jobs 2 --seed 1
fi
if [ "$STEP" = all ] || [ "$STEP" = check ]; then
  for t in 1 2; do
    { cat "$ROOT/dem/examples/oedometer_calibrated.toml"; printf '\n[specimen]\npacking_csv = "%s"\n' "$PACK"; } \
      > "$OUT/calibrated_t$t.toml"
    rm -rf "$OUT/calibrated_t$t"
    # The default wait policy: passive (set above for runs side by side on one
    # thread each) puts a thread to sleep at every barrier of a step, and a
    # 2-thread run then took 738 s instead of ~400 (session 47).
    env -u OMP_WAIT_POLICY OMP_NUM_THREADS=$t /usr/bin/time -f "threads $t: %e s wall, %U s user" \
      "$BIN" dem oedometer "$OUT/calibrated_t$t.toml" -o "$OUT/calibrated_t$t" 2>&1 | tail -1
  done
  cmp "$OUT/calibrated_t1/history.csv" "$OUT/calibrated_t2/history.csv" && echo "1 and 2 threads: same history.csv"
  python3 "$HERE/breakage_analysis.py" "$OUT/calibrated_t1"
fi
if [ "$STEP" = all ] || [ "$STEP" = shapes ]; then
  S="$OUT/shapes"
  mkdir -p "$S"
  "$BIN" synth --preset spheres -o "$S/stand_in.h5" > /dev/null
  "$BIN" measure "$S/stand_in.h5:/labels" -o "$S/stand_in.csv" > /dev/null
  rm -rf "$S/report"
  "$BIN" compare --xct "$S/stand_in.csv" --xct-strains 0.1548 --voxel-um 24.6 --dem "$OUT/calibrated_t1" \
    --no-imaged --no-track --no-plots -o "$S/report" > /dev/null
  grep -E "dem_ideal|dem_exact" "$S/report/shape_classes.csv"
fi

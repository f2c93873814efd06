#!/bin/sh
# DEM throughput and memory against the sphere count, tomograin vs LIGGGHTS 3.8
# (issue 23): the oedometer (rigid cylinder, fixed bottom platen, top platen
# at 0.1 m/s from the top of the highest grain, gravity, no breakage, the
# study's Hertz-Mindlin law and dt 1e-7 s) on the same packing for each N,
# a fixed number of steps (PSTEPS / N), tomograin on 1 and 2 threads,
# LIGGGHTS on 1 and 2 MPI ranks (only for N <= LG_MAX), run in turn.
# Packings: bench/dem/lattice_packing.py (a computed deposit: every sphere
# rests on the layer below, most in a pocket of three, so a contact network
# exists from the first step; the cylinder grows with N, the grains keep the
# study's sizes).
# Each run under /usr/bin/time -v: wall, user and system CPU, CPU share, peak
# RSS (LIGGGHTS on 2 ranks: the sum of the ranks' peaks, each rank under its
# own /usr/bin/time). Bytes per sphere = (peak RSS - peak RSS of the same
# code on a 10-sphere packing, once per rank) / N. Particle-steps/s = N x steps / the stepping loop's
# wall time (tomograin's summary line; LIGGGHTS' "Loop time"): set-up and
# file reading excluded on both sides (the whole-process wall is in the table).
# bench/dem/scaling_report.py then writes results.csv, table.md and scaling.png.
#
# Needs: BUILD_DIR/tomograin, liggghts + mpirun (scripts/install_deps.sh --bench),
# /usr/bin/python3 with numpy, scipy, matplotlib. Run from the repository root:
#   sh bench/dem/scaling.sh BUILD_DIR OUT_DIR ["10000 100000 1000000"]
# Environment: PSTEPS (particle-steps per run, default 3e8: ~40-60 s of one
# tomograin thread), LG_MAX (largest N given to LIGGGHTS, default 100000),
# REPEATS (runs of each code and core count per N, interleaved; default 1:
# the report gives medians and the range of the paired ratios).
# Also for each N: tomograin, 1 thread, skin 0 (a neighbour search every
# step), PSTEPS / 10 particle-steps: the search's cost per sphere against N.
set -eu
BUILD=${1:-build/release}; OUT=${2:-out/bench_dem_scaling}; SIZES=${3:-"10000 100000 1000000"}
PSTEPS=${PSTEPS:-300000000}; LG_MAX=${LG_MAX:-100000}; REPEATS=${REPEATS:-1}
ROOT=$(pwd); TG="$ROOT/$BUILD/apps/tomograin"; PY=/usr/bin/python3
[ -x "$TG" ] || TG="$ROOT/$BUILD/tomograin"
MKPLATE=/work/shared/peers/liggghts/make_plate.py  # the LIGGGHTS peer's platen mesh
[ -f "$MKPLATE" ] || MKPLATE="$ROOT/../shared/peers/liggghts/make_plate.py"
mkdir -p "$OUT"; cd "$OUT"
{
  echo "commit $(git -C "$ROOT" rev-parse --short HEAD)$(git -C "$ROOT" diff --quiet HEAD -- dem apps core || echo '+dirty')"
  echo "liggghts $(dpkg-query -W -f='${Version}' liggghts 2>/dev/null || echo '?')"
  echo "started $(date -u +%FT%TZ); uptime:$(uptime)"
  echo "cpu $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2), $(nproc) cores"
  echo "PSTEPS $PSTEPS LG_MAX $LG_MAX REPEATS $REPEATS"
} > conditions.txt
cat conditions.txt

# tg_run N THREADS DIR PACK R H0 STEPS [SKIN]
tg_run() {
  eps=$($PY -c "print(repr(($7 - 0.5) * 1e-7 * 0.1 / $6))")
  every=$(( $7 / 5 > 0 ? $7 / 5 : 1 ))
  rm -rf "$3"; mkdir -p "$3.in"
  cat > "$3.in/bench.toml" <<EOT
[specimen]
packing_csv = "$(realpath "$4")"
[walls]
cylinder_radius_m = $5
[run]
threads = $2
${8:+neighbour_skin_m = $8}
[oedometer]
target_strain = $eps
snapshot_strains = []
history_every_steps = $every
checkpoint_every_steps = 1000000000
[breakage]
enabled = false
EOT
  OMP_NUM_THREADS=$2 TOMOGRAIN_QUIET=1 /usr/bin/time -v -o "$3.in/time.txt" \
    "$TG" dem oedometer "$3.in/bench.toml" -o "$3" > "$3.in/stdout.txt" 2>&1
  echo "  tomograin $1 spheres, $2 thread(s): $(grep particle-steps "$3.in/stdout.txt")"
}

# lg_run N NP DIR DATA PLATE R STEPS
lg_run() {
  rm -rf "$3"; mkdir -p "$3"
  if [ "$2" = 1 ]; then
    /usr/bin/time -v -o "$3/time.txt" liggghts -in "$ROOT/bench/dem/in.scaling_data" -var px 1 \
      -var data "$4" -var plate "$5" -var R "$6" -var nsteps "$7" -log "$3/log" -echo none > "$3/screen" 2>&1
  else
    # Each rank under its own /usr/bin/time too: the outer one's peak RSS is
    # that of the largest process, the memory is the ranks' sum.
    /usr/bin/time -v -o "$3/time.txt" mpirun --allow-run-as-root -np "$2" sh -c '/usr/bin/time -v -o "$0/rank$OMPI_COMM_WORLD_RANK.time" "$@"' \
      "$3" liggghts -in "$ROOT/bench/dem/in.scaling_data" \
      -var px "$2" -var data "$4" -var plate "$5" -var R "$6" -var nsteps "$7" -log "$3/log" -echo none > "$3/screen" 2>&1
  fi
  echo "  liggghts $1 spheres, $2 rank(s): $(grep 'Loop time' "$3/screen" | tail -n 1)"
}

# prepare N: packing, LIGGGHTS data file and platen mesh; sets R, H0, STEPS
prepare() {
  $PY "$ROOT/bench/dem/lattice_packing.py" "$1" "pack_$1.csv" | tee "pack_$1.txt"
  R=$(sed -n 's/.*radius_m=\([^ ]*\).*/\1/p' "pack_$1.txt")
  H0=$(sed -n 's/.*H0_m=\([^ ]*\).*/\1/p' "pack_$1.txt")
  half=$($PY -c "print(repr($R + 0.0015))")
  $PY "$ROOT/bench/dem/csv_to_liggghts.py" "pack_$1.csv" "pack_$1.data" 2180 "$half"
  # Square platen mesh covering the cylinder, triangles of ~4 mm.
  $PY "$MKPLATE" "$($PY -c "print($R + 0.001)")" \
    "$($PY -c "import math; print(max(8, math.ceil(2 * ($R + 0.001) / 0.004)))")" "plate_$1.stl"
}

echo "empty runs (10 spheres, 1000 steps): the RSS baseline"
prepare 10
tg_run 10 1 tg_10_t1 "pack_10.csv" "$R" "$H0" 1000
[ "$LG_MAX" -ge 10 ] && lg_run 10 1 lg_10_np1 "pack_10.data" "plate_10.stl" "$R" 1000
for N in $SIZES; do
  prepare "$N"
  STEPS=$(( PSTEPS / N ))
  rep=1
  while [ "$rep" -le "$REPEATS" ]; do
    # Repeats interleaved, each code's run beside the other's, so that a
    # ratio compares runs made a minute apart (this VM's speed drifts by
    # half over minutes: bench/dem/RESULTS.md).
    sfx=""; [ "$rep" -gt 1 ] && sfx="_r$rep"
    echo "N = $N: $STEPS steps, repeat $rep of $REPEATS (uptime:$(uptime | sed 's/.*average://'))"
    tg_run "$N" 1 "tg_${N}_t1$sfx" "pack_$N.csv" "$R" "$H0" "$STEPS"
    [ "$N" -le "$LG_MAX" ] && lg_run "$N" 1 "lg_${N}_np1$sfx" "pack_$N.data" "plate_$N.stl" "$R" "$STEPS"
    tg_run "$N" 2 "tg_${N}_t2$sfx" "pack_$N.csv" "$R" "$H0" "$STEPS"
    [ "$N" -le "$LG_MAX" ] && lg_run "$N" 2 "lg_${N}_np2$sfx" "pack_$N.data" "plate_$N.stl" "$R" "$STEPS"
    rep=$((rep + 1))
  done
  # Neighbour search at every step (skin 0: the list is rebuilt whenever a
  # sphere has moved): its cost per sphere against N, one thread.
  tg_run "$N" 1 "tgskin0_${N}_t1" "pack_$N.csv" "$R" "$H0" "$(( PSTEPS / 10 / N ))" 0
done
echo "ended $(date -u +%FT%TZ); uptime:$(uptime)" >> conditions.txt
$PY "$ROOT/bench/dem/scaling_report.py" .

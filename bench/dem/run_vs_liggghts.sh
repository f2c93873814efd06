#!/bin/sh
# Oedometer without breakage, tomograin vs LIGGGHTS 3.8 on the same packing
# and parameters, to 10 % strain; particle-steps/s on 1 and 2 cores.
# Needs: build/<dir>/tomograin, `liggghts` and `mpirun` (apt-get install
# liggghts openmpi-bin), /usr/bin/python3. Run from the repository root:
#   sh bench/dem/run_vs_liggghts.sh BUILD_DIR OUT_DIR [packing.csv]
set -eu
BUILD=${1:-build}; OUT=${2:-out/bench_dem}; PACK=${3:-}
ROOT=$(pwd); mkdir -p "$OUT"; cd "$OUT"
TG="$ROOT/$BUILD/tomograin"
if [ -z "$PACK" ]; then
  "$TG" dem pack "$ROOT/dem/examples/oedometer.toml" -o packing.csv | tee pack.txt
  PACK=packing.csv
fi
/usr/bin/python3 "$ROOT/bench/dem/csv_to_liggghts.py" "$PACK" packing.data
/usr/bin/python3 /work/shared/peers/liggghts/make_plate.py 0.0085 8 plate.stl 2>/dev/null || \
  /usr/bin/python3 "$ROOT/../shared/peers/liggghts/make_plate.py" 0.0085 8 plate.stl
N=$(($(wc -l < "$PACK") - 1))
cat > bench.toml <<EOT
[specimen]
packing_csv = "$(realpath "$PACK")"
[oedometer]
target_strain = 0.10
snapshot_strains = [0.0, 0.10]
[breakage]
enabled = false
EOT
for t in 1 2; do
  OMP_NUM_THREADS=$t TOMOGRAIN_QUIET=1 /usr/bin/time -f "tomograin $t threads: %e s wall, %U s user, %S s sys, %P CPU" \
    "$TG" dem oedometer bench.toml -o "tg_np$t" 2>&1 | tee "tg_np$t.txt"
done
for np in 1 2; do
  start=$(date +%s.%N)
  if [ $np = 1 ]; then
    /usr/bin/time -f "liggghts np1: %e s wall, %U s user, %S s sys, %P CPU" -o time.np1 \
      liggghts -in "$ROOT/bench/dem/in.compress_data" -var tag np1 -var px 1 -log log.np1 -echo none > screen.np1 2>&1
  else
    /usr/bin/time -f "liggghts np2: %e s wall, %U s user, %S s sys, %P CPU" -o time.np2 \
      mpirun --allow-run-as-root -np 2 liggghts -in "$ROOT/bench/dem/in.compress_data" -var tag np2 -var px 2 -log log.np2 -echo none > screen.np2 2>&1
  fi
  end=$(date +%s.%N)
  steps=$(tail -n 1 stress_strain_np$np.txt | awk '{print $1}')
  echo "liggghts np$np: $N spheres, $steps steps, $(echo "$end - $start" | bc) s wall, $(echo "$N * $steps / ($end - $start)" | bc) particle-steps/s (incl. start-up)" | tee "lg_np$np.txt"
  cat time.np$np
done
/usr/bin/python3 "$ROOT/bench/dem/compare.py" tg_np1/history.csv stress_strain_np1.txt | tee compare.txt

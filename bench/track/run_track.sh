#!/usr/bin/env bash
# bench/track: `tomograin track` on data_synth oedometer series (zeolite-stages
# with [stages] motion = "oedometer"): time and memory per stage, and the
# accuracy table on the truth labels (the tracker alone) and on labels
# segmented from the grey scans (`tomograin segment`, defaults).
#
#   bench/track/run_track.sh [BUILD] [SIZES] [SEEDS] [GAP_VOX]
#   bench/track/run_track.sh build/release "256 512" "11" 1.0
#   PSF=1.0 NOISE=2230 bench/track/run_track.sh build/release 256 11 1.0
#
# PSF (voxels) and NOISE (grey levels; the contrast is 29000, so CNR 13 is
# NOISE 2230) set data_synth's [imaging] psf_sigma_vox and noise_sigma
# (defaults 0.7 and 900: CNR 32); bench/track/blind_range.py sweeps them.
# KIND=segmented skips the truth-label run (the tracker alone does not see
# the imaging).
#
# Work files in ${TMPDIR:-/tmp}/tomograin_track_bench; one CSV of figures per
# (size, seed, labels) and the /usr/bin/time -v lines of each track run.
set -eu
B=${1:-build/release}
SIZES=${2:-256}
SEEDS=${3:-11}
GAP=${4:-1.0}
T=$B/apps/tomograin
E=$B/bench/track/track_eval
W=${TMPDIR:-/tmp}/tomograin_track_bench
mkdir -p "$W"
export TOMOGRAIN_QUIET=1
echo "== machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); gap $GAP voxels"
for n in $SIZES; do
  for seed in $SEEDS; do
    d=$W/n${n}_s${seed}_g${GAP}${PSF:+_p$PSF}${NOISE:+_n$NOISE}
    mkdir -p "$d"
    printf '[stages]\nmotion = "oedometer"\ngap_vox = %s\n' "$GAP" > "$d/scene.toml"
    if [[ -n ${PSF:-}${NOISE:-} ]]; then
      printf '[imaging]\n' >> "$d/scene.toml"
      [[ -z ${PSF:-} ]] || printf 'psf_sigma_vox = %s\n' "$PSF" >> "$d/scene.toml"
      [[ -z ${NOISE:-} ]] || printf 'noise_sigma = %s\n' "$NOISE" >> "$d/scene.toml"
    fi
    if [[ ! -f $d/run_lineage.csv ]]; then
      "$T" synth --preset zeolite-stages --scene "$d/scene.toml" --size "$n" --seed "$seed" -o "$d/run.h5" > "$d/synth.log"
    fi
    seg=()
    truth=()
    for s in 0 1 2 3 4; do
      [[ -f $d/seg$s.h5 ]] || "$T" segment "$d/run_stage$s.h5" -o "$d/seg$s.h5" > /dev/null
      seg+=("$d/seg$s.h5")
      truth+=("$d/run_stage$s.h5")
    done
    for kind in ${KIND:-truth segmented}; do
      if [[ $kind == truth ]]; then in=("${truth[@]}"); else in=("${seg[@]}"); fi
      /usr/bin/time -v "$T" track "${in[@]}" -o "$d/track_$kind" > "$d/track_$kind.log" 2> "$d/track_$kind.time"
      echo "-- ${n}^3 seed $seed $kind labels"
      grep -E "^stage" "$d/track_$kind.log"
      grep -E "Elapsed|User time|System time|Maximum resident" "$d/track_$kind.time" | sed 's/^\s*/   /'
      if [[ $kind == truth ]]; then
        "$E" "$d/run_lineage.csv" "$d/track_$kind/lineage.csv" > "$d/eval_$kind.csv" 2> "$d/eval_$kind.err"
      else
        "$E" "$d/run_lineage.csv" "$d/track_$kind/lineage.csv" --labels "${seg[@]}" --truth "${truth[@]}" \
          > "$d/eval_$kind.csv" 2> "$d/eval_$kind.err"
      fi
      paste -sd' ' "$d/eval_$kind.csv"
    done
  done
done

#!/usr/bin/env bash
# tomograin track on bench/track/blind_series.py's stage series (an
# independent generator: moving platen at either end of a scan window,
# label numbers permuted every stage), on the truth labels and on labels
# segmented with the defaults; scored by track_eval (all events, and those
# of parents clear of the faces: *_interior_*).
#   bench/track/run_blind_series.sh [BUILD] [SEEDS] [SIZE] [RADIUS] [PLATEN] [extra blind_series.py args...]
#   bench/track/run_blind_series.sh build/release "2 3" 192 12 bottom
# Series are kept in ${TMPDIR:-/tmp}/tomograin_blind_series and reused.
set -eu
B=${1:-build/release}
SEEDS=${2:-2}
SIZE=${3:-192}
R=${4:-12}
PLATEN=${5:-bottom}
shift $(( $# < 5 ? $# : 5 ))
HERE=$(cd "$(dirname "$0")" && pwd)
T=$B/apps/tomograin
E=$B/bench/track/track_eval
W=${TMPDIR:-/tmp}/tomograin_blind_series
mkdir -p "$W"
export TOMOGRAIN_QUIET=1
echo "== machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
for seed in $SEEDS; do
  p=$W/n${SIZE}_r${R}_${PLATEN}_s${seed}${*:+_$(echo "$*" | tr -c 'A-Za-z0-9.\n' '_')}
  [[ -f ${p}_lineage.csv ]] || /usr/bin/python3 "$HERE/blind_series.py" -o "$p" --size "$SIZE" --radius "$R" \
    --platen "$PLATEN" --seed "$seed" "$@" > "$p.log"
  seg=()
  truth=()
  nst=$(ls "${p}"_stage*.h5 | wc -l)  # --strains sets the number of stages (5 by default)
  for ((s = 0; s < nst; s++)); do
    [[ -f ${p}_seg$s.h5 ]] || "$T" segment "${p}_stage$s.h5:/scan" -o "${p}_seg$s.h5" --grain-radius-vox "$R" > /dev/null
    seg+=("${p}_seg$s.h5")
    truth+=("${p}_stage$s.h5")
  done
  for kind in truth segmented; do
    if [[ $kind == truth ]]; then in=("${truth[@]}"); else in=("${seg[@]}"); fi
    "$T" track "${in[@]}" -o "${p}_track_$kind" > "${p}_track_$kind.log"
    echo "-- ${SIZE}^3 R $R platen $PLATEN seed $seed, $kind labels"
    if [[ $kind == truth ]]; then
      "$E" "${p}_lineage.csv" "${p}_track_$kind/lineage.csv" > "${p}_eval_$kind.csv" 2> "${p}_eval_$kind.err"
    else
      "$E" "${p}_lineage.csv" "${p}_track_$kind/lineage.csv" --labels "${seg[@]}" --truth "${truth[@]}" \
        > "${p}_eval_$kind.csv" 2> "${p}_eval_$kind.err"
    fi
    tr '\n' ' ' < "${p}_eval_$kind.csv"
    echo
  done
done

#!/usr/bin/env bash
# The full breakage oedometer of the reference study (issue 7): the study's
# packing (pluviation with the defaults of dem/examples/oedometer.toml:
# 910 grains, frictionless deposition), Table 1 parameters, breakage on
# (selective density scaling to dt >= 1e-8 s, sub-limit spheres removed as
# fines), to 15.48 % strain; then the closing figures (breakage_analysis.py).
# Usage: bench/dem/breakage_full.sh TOMOGRAIN_BINARY RUNDIR [THREADS=2] [TARGET_STRAIN=0.1548]
# Wall/CPU time: /usr/bin/time -v output at the end of RUNDIR.log. Long
# (tens of minutes): run under `nice -n 10` on a shared machine.
set -euo pipefail
BIN=$(realpath "${1:?path to the tomograin binary}")
export TOMOGRAIN="$BIN"  # breakage_analysis.py asks it for the yield
RUN=${2:?run folder}
THREADS=${3:-2}
TARGET=${4:-0.1548}
# The study's scans, or only the start and the end for a shorter run.
SNAPS="[0.0, 0.044, 0.0712, 0.1128, 0.1548]"
[ "$TARGET" = 0.1548 ] || SNAPS="[0.0, $TARGET]"
HERE=$(cd "$(dirname "$0")" && pwd)
EX="$HERE/../../dem/examples/oedometer.toml"
# The requested thread count for both steps, with libgomp's default wait
# policy (spin a while, then sleep; less spinning on oversubscribed cores):
# OMP_WAIT_POLICY=passive, used here before, puts a thread to sleep at every
# barrier of a step (2 threads: 2.4x the default's wall time over the first
# 9 % of strain, session 47).
export OMP_NUM_THREADS=$THREADS
mkdir -p "$RUN.work"
PACK="$RUN.work/packing.csv"
[ -f "$PACK" ] || "$BIN" dem pack "$EX" -o "$PACK"
sed -e "s|^packing_csv = \"\"|packing_csv = \"$(realpath "$PACK")\"|" \
    -e "s|^threads = 0 |threads = $THREADS |" \
    -e "s|^target_strain = 0.1548 |target_strain = $TARGET |" \
    -e "s|^snapshot_strains = \[0.0, 0.044, 0.0712, 0.1128, 0.1548\]|snapshot_strains = $SNAPS|" \
    "$EX" > "$RUN.work/oedometer.toml"
/usr/bin/time -v "$BIN" dem oedometer "$RUN.work/oedometer.toml" -o "$RUN" 2> "$RUN.log"
python3 "$HERE/breakage_analysis.py" "$RUN"

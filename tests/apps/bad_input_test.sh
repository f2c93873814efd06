#!/usr/bin/env bash
# Hostile inputs to the CLI: each must exit 2 with exactly one line on stderr
# naming the file, and leave no output behind.
set -u
TG=$1
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
fails=0; passes=0

# expect_bad NAME PATTERN -- COMMAND...: exit 2, one stderr line matching PATTERN, no out.* left.
expect_bad() {
  local name=$1 pattern=$2; shift 3
  rm -rf out.* .out.*
  "$@" >stdout.txt 2>stderr.txt
  local rc=$? lines
  lines=$(wc -l <stderr.txt)
  if [[ $rc -ne 2 || $lines -ne 1 ]] || ! grep -q -- "$pattern" stderr.txt || compgen -G "out.*" >/dev/null || compgen -G ".out.*" >/dev/null; then
    echo "FAIL $name: rc=$rc lines=$lines stderr=$(cat stderr.txt) left=$(ls -A | grep out || true)"
    fails=$((fails+1))
  else
    echo "ok   $name: $(cat stderr.txt)"
    passes=$((passes+1))
  fi
}

# A valid 4x64x64 u16 volume to damage.
printf '{"shape_zyx":[4,64,64],"dtype":"uint16","voxel_size_um":10}' > good.json
head -c 32768 /dev/urandom > good.raw
"$TG" convert good.json -o good.tif >/dev/null || { echo "FAIL setup"; exit 1; }
size=$(stat -c %s good.tif)

head -c $((size / 2)) good.tif > cut.tif
expect_bad "truncated TIFF" "cut.tif: truncated" -- "$TG" convert cut.tif -o out.h5

head -c 200 good.tif > header_only.tif
expect_bad "TIFF cut inside page data" "header_only.tif" -- "$TG" convert header_only.tif -o out.h5

echo "not a tiff at all" > junk.tif
expect_bad "wrong header" "junk.tif: not a readable TIFF" -- "$TG" info junk.tif

mkdir mixed
"$TG" convert good.tif -o mixed/ >/dev/null
printf '{"shape_zyx":[1,64,60],"dtype":"uint16"}' > small.json; head -c 7680 /dev/urandom > small.raw
"$TG" convert small.json -o mixed/slice_0099.tif >/dev/null
expect_bad "mixed slice sizes" "mixed slice sizes" -- "$TG" convert mixed -o out.h5
expect_bad "crop outside the volume" "range 0:9 is empty or outside good.tif" -- "$TG" convert good.tif -o out.h5 --crop 0:9,:,:
expect_bad "crop not three ranges" "Z0:Z1,Y0:Y1,X0:X1" -- "$TG" convert good.tif -o out.h5 --crop 0:2

printf '{"shape_zyx":[4,64,65],"dtype":"uint16","files":{"volume_raw":"good.raw"}}' > wrongsize.json
expect_bad "sidecar with wrong size" "good.raw: file has 32768 bytes" -- "$TG" convert wrongsize.json -o out.tif

printf '{"shape_zyx":[100000000,100000000,100000000],"dtype":"uint16","files":{"volume_raw":"good.raw"}}' > absurd.json
expect_bad "absurd shape (overflow)" "64-bit" -- "$TG" convert absurd.json -o out.tif

printf '{"shape_zyx":[100000,100000,100000],"dtype":"uint16","files":{"volume_raw":"good.raw"}}' > huge.json
expect_bad "absurd shape (size mismatch before allocation)" "huge.json" -- "$TG" info huge.json

printf '{"shape_zyx":[2,2,2],"dtype":"float32"}' > nan.json
printf '\x00\x00\x80\x3f\x00\x00\xc0\x7f\x00\x00\x80\x3f\x00\x00\x80\x3f\x00\x00\x80\x3f\x00\x00\x80\x7f\x00\x00\x80\x3f\x00\x00\x80\x3f' > nan.raw
expect_bad "NaN/Inf in float input" "2 NaN/Inf voxel(s), first at (z,y,x)=(0,0,1)" -- "$TG" convert nan.json -o out.h5 --to uint16

"$TG" convert good.tif -o g.h5 >/dev/null
expect_bad "missing HDF5 dataset" "g.h5:/labels: no such dataset" -- "$TG" info g.h5:/labels
# A file holding a scan (/scan) and its labels (/labels): the default dataset
# is the labels, so segment and measure --grey name the grey one to use.
/usr/bin/python3 -c "import h5py, numpy as np; f = h5py.File('both.h5', 'w'); f['scan'] = np.full((4, 8, 8), 1000, np.uint16); f['labels'] = np.ones((4, 8, 8), np.uint32)"
expect_bad "labels where a scan is expected" "both.h5: its default dataset holds uint32 labels.*name it: both.h5:/scan" -- "$TG" segment both.h5 -o out.h5
expect_bad "rings of a label volume" "--rings works on uint16 or float32" -- "$TG" convert both.h5:/labels -o out.h5 --rings
expect_bad "ring axis not Y,X" "--ring-axis takes Y,X" -- "$TG" convert both.h5:/scan -o out.h5 --rings --ring-axis=-3,4
expect_bad "labels as --grey" "both.h5: its default dataset holds uint32 labels.*both.h5:/scan" -- "$TG" measure both.h5 --grey both.h5 -o out.csv --voxel-um 10
expect_bad "missing input" "none.tif: no such file" -- "$TG" convert none.tif -o out.h5
expect_bad "unknown format" "unknown volume format" -- "$TG" convert good.tif -o out.xyz
printf '{"shape_zyx":[1,1,2],"dtype":"float32"}' > f.json; printf '\x00\x00\x80\x3f\x00\x00\x00\x40' > f.raw
expect_bad "bad --range" "--range must be" -- "$TG" convert f.json -o out.h5 --to uint16 --range 5,1
# Out-of-range options of measure are refused before its parallel loops (an
# exception there used to abort the process, exit 134).
"$TG" synth --preset spheres --size 32 -o lab.h5 >/dev/null
expect_bad "measure --face-offset 0" "--face-offset must be in (0, 1]" -- "$TG" measure lab.h5 -o out.csv --face-offset 0
expect_bad "unknown option" "tomograin:" -- "$TG" convert good.tif -o out.h5 --frobnicate
# --feret takes `exact` or a whole number, the same rule in measure and compare
# (compare read "60abc" as 60 before they shared apps/main.cpp's parser).
expect_bad "measure --feret 60abc" "--feret must be a number of orientations (>= 3) or 'exact', got '60abc'" -- "$TG" measure lab.h5 -o out.csv --feret 60abc
expect_bad "compare --feret 60abc" "--feret must be a number of orientations (>= 3) or 'exact', got '60abc'" -- "$TG" compare --xct lab.h5 -o out.report --dem . --feret 60abc

# A scan mostly saturated at 65535 (60 % of the voxels): a threshold on the
# rest would be meaningless (issue 19: a saturated block silently ruined it).
printf '{"shape_zyx":[4,64,64],"dtype":"uint16","voxel_size_um":10}' > sat.json
{ head -c 19660 /dev/zero | tr '\0' '\377'; head -c 13108 /dev/urandom; } > sat.raw
expect_bad "mostly saturated scan" "sat.json: 60 % of the voxels are saturated" -- "$TG" segment sat.json -o out.h5 --grain-radius-vox 5

# dem calibrate (issue 21): config, target and ranges checked before the
# output folder exists (no run starts on a config that cannot run).
printf '[oedometer]\ntarget_strain = 0.05\nsnapshot_strains = [0.0]\n' > cal.toml
printf 'strain,stress_Pa\n0.01,1e5\n0.04,1e6\n' > curve.csv
printf '[oedometer]\ntarget_strain = 0.05\nsnapshot_strains = [0.0]\n[breakage]\nsigma_t0 = 1e7\n' > cal_typo.toml
expect_bad "calibrate: unknown config key" "cal_typo.toml: unknown key 'breakage.sigma_t0'" -- "$TG" dem calibrate cal_typo.toml --target curve.csv -o out.cal
printf 'strain,stress_Pa\n' > empty.csv
expect_bad "calibrate: empty target curve" "empty.csv: the stress-strain curve has no rows" -- "$TG" dem calibrate cal.toml --target empty.csv -o out.cal
printf '[target]\nstress_strain_csv = "curve.csv"\n[parameters]\nbond_radius_multiplier = [1.5, 0.9]\n' > range.toml
expect_bad "calibrate: bad range" "range.toml: parameters.bond_radius_multiplier must be \[min, max\]" -- "$TG" dem calibrate cal.toml --target range.toml -o out.cal
printf '[target]\nstress_strain_csv = "curve.csv"\nyield = 2e6\n' > tkey.toml
expect_bad "calibrate: unknown target key" "tkey.toml: unknown key 'target.yield'" -- "$TG" dem calibrate cal.toml --target tkey.toml -o out.cal
printf '[target]\nstress_strain_csv = "curve.csv"\n[crush]\nbonds_broken = -5.0\n' > crushneg.toml
expect_bad "calibrate: negative crush target" "crushneg.toml: crush.bonds_broken must be > 0" -- "$TG" dem calibrate cal.toml --target crushneg.toml -o out.cal
printf '[crush]\nbonds_broken = 100.0\ndiameter = 1e-3\n' > crushkey.toml
expect_bad "calibrate: unknown crush key" "crushkey.toml: unknown key 'crush.diameter'" -- "$TG" dem calibrate cal.toml --target crushkey.toml -o out.cal
printf '[specimen]\npacking_csv = "nope.csv"\n[oedometer]\ntarget_strain = 0.05\nsnapshot_strains = [0.0]\n' > cal_nopack.toml
expect_bad "calibrate: missing packing" "nope.csv" -- "$TG" dem calibrate cal_nopack.toml --target curve.csv -o out.cal
printf 'strain,stress_Pa\n0.01,1e5\n0.09,1e6\n' > far.csv
expect_bad "calibrate: target beyond the run" "far.csv: target strains reach 0.09" -- "$TG" dem calibrate cal.toml --target far.csv -o out.cal

# NaN policy: `info` reports instead of refusing.
"$TG" info nan.json | grep -q "2 NaN/Inf voxels" && { echo "ok   info reports NaN"; passes=$((passes+1)); } || { echo "FAIL info NaN"; fails=$((fails+1)); }

echo "$passes passed, $fails failed"
[[ $fails -eq 0 ]]

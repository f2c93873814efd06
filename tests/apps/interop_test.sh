#!/usr/bin/env bash
# TIFFs written by `tomograin convert` must open in other tools: libtiff's
# tiffinfo, and Python tifffile (Debian's python3-tifffile) with the same
# values and the voxel size in ImageJ metadata. Also float -> u16 normalisation
# checked against numpy on the same data.
set -eu
TG=$1
SRC=$2
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
/usr/bin/python3 "$SRC/make_volumes.py" "$W"
for t in u8 u16 u32 f32; do
  "$TG" convert "$t.json" -o "$t.tif" >/dev/null
  "$TG" convert "$t.tif" -o "${t}_slices/" >/dev/null
  "$TG" convert "${t}_slices" -o "$t.h5" >/dev/null
  "$TG" convert "$t.h5" -o "${t}_back.json" >/dev/null
  tiffinfo "$t.tif" >/dev/null
  cmp "$t.raw" "${t}_back.raw"   # TIFF -> folder -> HDF5 -> raw is bit-exact
done
# --crop from every format (each reads only the box's slices): the same box as numpy's slicing
for src in u16.tif u16_slices u16.json u16.h5; do
  "$TG" convert "$src" -o "crop_${src%%.*}_${src##*.}.h5" --crop 1:4,2:30,:40 >/dev/null
done
"$TG" convert f32.json -o norm.h5 --to uint16 --range auto > norm.txt
"$TG" convert f32.json -o norm_given.tif --to uint16 --range -100,400 >/dev/null
/usr/bin/python3 "$SRC/check_volumes.py" "$W"

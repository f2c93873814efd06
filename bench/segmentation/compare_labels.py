#!/usr/bin/python3
"""Compares the /labels datasets of two HDF5 files voxel for voxel, 64 slices
at a time (memory: 2 x 64 slices), e.g. `segment` in one piece against
`segment --memory-limit` (slab by slab). Prints the differing voxel count;
exit status 1 when any voxel differs.

    /usr/bin/python3 bench/segmentation/compare_labels.py one_piece.h5 slabs.h5
"""
import sys

import h5py
import numpy as np

a = h5py.File(sys.argv[1], 'r')['/labels']
b = h5py.File(sys.argv[2], 'r')['/labels']
assert a.shape == b.shape, (a.shape, b.shape)
diff = 0
top = 0
for z in range(0, a.shape[0], 64):
    x = a[z:z + 64]
    y = b[z:z + 64]
    diff += int(np.count_nonzero(x != y))
    top = max(top, int(x.max()), int(y.max()))
print(f"{sys.argv[1]} vs {sys.argv[2]}: shape {a.shape}, max label {top}, differing voxels {diff}")
sys.exit(1 if diff else 0)

#!/usr/bin/python3
"""Mirror-tile a scan N x N x N times into a larger HDF5 scan (issue 23's
larger-than-memory bench): each copy is flipped across the seams, so the grey
levels are continuous, and a specimen that touches no face of the source
gives exactly N^3 copies of its grains.

  tile_scan.py SRC.h5[:/volume] N OUT.h5[:/volume]

Writes uint16 in chunks of 16 x 256 x 256 (as tomograin writes volumes),
uncompressed, 16 slices at a time (memory: one source volume and a slab of
the output), with the source's voxel_size_m and origin_m attributes.
"""
import sys

import h5py
import numpy as np


def spec(s, default):
    return s.split(":", 1) if ":" in s else (s, default)


def main():
    src, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    sp, sd = spec(src, "volume")
    op, od = spec(out, "volume")
    with h5py.File(sp, "r") as f:
        v = f[sd][()]
        attrs = {k: f[sd].attrs[k] for k in f[sd].attrs}
    nz, ny, nx = v.shape
    # One row of copies in y and x, flipped alternately.
    row = np.concatenate([v if b % 2 == 0 else v[:, ::-1, :] for b in range(n)], axis=1)
    row = np.concatenate([row if c % 2 == 0 else row[:, :, ::-1] for c in range(n)], axis=2)
    del v
    shape = (nz * n, ny * n, nx * n)
    with h5py.File(op, "w") as f:
        d = f.create_dataset(od.lstrip("/"), shape=shape, dtype=np.uint16,
                             chunks=(16, min(256, shape[1]), min(256, shape[2])))
        for k, val in attrs.items():
            d.attrs[k] = val
        for z0 in range(0, shape[0], 16):
            z1 = min(shape[0], z0 + 16)
            ks = np.arange(z0, z1)
            a, r = ks // nz, ks % nz
            src_k = np.where(a % 2 == 0, r, nz - 1 - r)
            d[z0:z1] = row[src_k]
            if z0 % 256 == 0:
                print(f"  slices {z0}..{z1 - 1} of {shape[0]}", flush=True)
    print(f"wrote {op}:/{od.lstrip('/')} {shape} uint16")


if __name__ == "__main__":
    main()

"""Independent checks with tifffile/h5py/numpy of what tomograin wrote."""
import json, sys
import numpy as np
import tifffile, h5py
w = sys.argv[1]
fails = 0
def check(cond, what):
    global fails
    print(("ok   " if cond else "FAIL ") + what)
    fails += not cond
for k, dt in [("u8", "<u1"), ("u16", "<u2"), ("u32", "<u4"), ("f32", "<f4")]:
    ref = np.fromfile(f"{w}/{k}.raw", dtype=dt).reshape(5, 33, 47)
    with tifffile.TiffFile(f"{w}/{k}.tif") as t:
        arr = t.asarray()
        check(arr.dtype == ref.dtype and np.array_equal(arr, ref), f"tifffile reads {k}.tif bit-exact")
        ij = t.imagej_metadata or {}
        check(abs(float(ij.get("spacing", 0)) - 12.3) < 1e-9 and ij.get("unit") == "micron", f"{k}.tif ImageJ spacing 12.3 micron")
        xres = t.pages[0].tags["XResolution"].value
        check(abs(xres[1] / xres[0] - 12.3) < 1e-4, f"{k}.tif XResolution = 1/12.3 per micron")
    with h5py.File(f"{w}/{k}.h5", "r") as f:
        check(np.array_equal(f["volume" if k != "u32" else "labels"][...], ref), f"h5py reads {k}.h5 bit-exact")
        vs = f["volume" if k != "u32" else "labels"].attrs["voxel_size_m"]
        check(np.allclose(vs, 12.3e-6, rtol=1e-6), f"{k}.h5 voxel_size_m attribute")
# convert --crop 1:4,2:30,:40 of u16 from TIFF, a slice folder, raw and HDF5: numpy's box,
# its origin moved to the box's corner (slices and rows of 12.3 um)
u16 = np.fromfile(f"{w}/u16.raw", dtype="<u2").reshape(5, 33, 47)
for src in ["u16_tif", "u16_slices_u16_slices", "u16_json", "u16_h5"]:
    with h5py.File(f"{w}/crop_{src}.h5", "r") as f:
        check(np.array_equal(f["volume"][...], u16[1:4, 2:30, :40]), f"--crop of {src} = numpy's box")
        check(np.allclose(f["volume"].attrs["origin_m"], [12.3e-6, 2 * 12.3e-6, 0], rtol=1e-6, atol=1e-12),
              f"--crop of {src}: origin at the box's corner")
# float -> u16: the study's linear map of [lo, hi] to [0, 65535] with clipping, rounded.
f32 = np.fromfile(f"{w}/f32.raw", dtype="<f4").reshape(5, 33, 47).astype(np.float64)
given = tifffile.imread(f"{w}/norm_given.tif")
expect = np.clip(np.round(65535.0 * (f32 + 100.0) / 500.0), 0, 65535).astype(np.uint16)
check(np.abs(given.astype(int) - expect.astype(int)).max() <= 1, "--range -100,400 matches numpy linear map (+-1 rounding)")
with h5py.File(f"{w}/norm.h5", "r") as f:
    auto = f["volume"][...]
# "auto" = the grey values at which the cumulative histogram first reaches 0.01 % and 99.99 %
# (numpy's inverted_cdf definition; its default interpolates between order statistics).
lo, hi = np.percentile(f32, [0.01, 99.99], method="inverted_cdf")
import re
txt = open(f"{w}/norm.txt").read()
m = re.search(r"\[([-0-9.e+]+), ([-0-9.e+]+)\] -> \[0, 65535\]", txt)
check(m is not None and abs(float(m.group(1)) - lo) < 1e-3 * (hi - lo) and abs(float(m.group(2)) - hi) < 1e-3 * (hi - lo),
      f"--range auto printed [{m.group(1) if m else '?'}, {m.group(2) if m else '?'}] = numpy inverted_cdf [{lo:.6g}, {hi:.6g}]")
expect = np.clip(np.round(65535.0 * (f32 - lo) / (hi - lo)), 0, 65535)
check(np.abs(auto.astype(float) - expect).max() <= 65535 * 2e-3, "--range auto ~ numpy 0.01/99.99 percentiles")
sys.exit(1 if fails else 0)

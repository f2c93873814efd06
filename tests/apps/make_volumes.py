"""Writes u8/u16/u32/f32 test volumes as raw + JSON sidecars."""
import json, sys
import numpy as np
w = sys.argv[1]
rng = np.random.default_rng(7)
shape = (5, 33, 47)
vols = {"u8": rng.integers(0, 256, shape, dtype=np.uint8),
        "u16": rng.integers(0, 65536, shape, dtype=np.uint16),
        "u32": rng.integers(0, 2**32, shape, dtype=np.uint32),
        "f32": rng.normal(100.0, 50.0, shape).astype(np.float32)}
names = {"u8": "uint8", "u16": "uint16", "u32": "uint32", "f32": "float32"}
for k, v in vols.items():
    v.astype(v.dtype.newbyteorder("<")).tofile(f"{w}/{k}.raw")
    with open(f"{w}/{k}.json", "w") as f:
        json.dump({"shape_zyx": list(shape), "dtype": names[k], "voxel_size_um": [12.3, 12.3, 12.3]}, f)

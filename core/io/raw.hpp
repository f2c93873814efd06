// Raw binary volume + JSON sidecar. The sidecar (the name users pass) says:
//   {
//     "shape_zyx": [nz, ny, nx],                 required
//     "dtype": "uint16",                         uint8|uint16|uint32|float32 (default uint16)
//     "byte_order": "little",                    little|big (default little)
//     "voxel_size_m": [z, y, x] or a number,     or "voxel_size_um" / "voxel_mm"
//     "origin_m": [z, y, x],                     optional
//     "header_bytes": 0,                         bytes to skip at the start of the raw file
//     "files": {"volume_raw": "scan.raw"}        default: sidecar name with .raw
//   }
// The raw file's size must equal header_bytes + voxels * bytes per voxel
// exactly; anything else is an InputError naming both sizes. The peers'
// scikit-image pipeline reads the same sidecar (shape_zyx, files.volume_raw).
#pragma once
#include <string>

#include "core/dtype.hpp"

namespace tg {

// `slices`: only their bytes are read; the origin moves to the first
// (core/io/volume_io.hpp, ReadOptions::slices).
AnyVolume read_raw(const std::string& json_path, bool progress, SliceRange slices = {});
// The shape the sidecar gives (checked against the raw file's size).
Shape raw_shape(const std::string& json_path);
// Writes JSON_PATH and the raw file beside it (stem + ".raw"), little-endian.
void write_raw(const AnyVolume& v, const std::string& json_path, bool progress);
template <class T>
void write_raw(const Volume<T>& v, const std::string& json_path, bool progress);

}  // namespace tg

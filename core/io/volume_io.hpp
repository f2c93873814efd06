// Reading and writing volumes by file name. The format follows the name:
//   *.tif, *.tiff            multi-page TIFF (BigTIFF past 4 GB)
//   a folder                 TIFF slices, sorted naturally (slice_9 before slice_10)
//   *.json (+ raw beside)    raw + JSON sidecar, see core/io/raw.hpp
//   *.h5, *.hdf5[:/path]     HDF5; default dataset /volume (or /labels for u32)
// Every reader validates sizes against the file and available memory and
// throws InputError("FILE: problem"); every writer is atomic.
#pragma once
#include <string>

#include "core/dtype.hpp"

namespace tg {

enum class NonFinite { error, allow };

struct ReadOptions {
  double voxel_um = 0;  // > 0: override (or supply) the file's voxel size, micrometres
  // Float volumes with NaN/Inf voxels: `error` (default) rejects the file with
  // the count and the first position; `allow` keeps them (e.g. for `info`).
  NonFinite nonfinite = NonFinite::error;
  bool progress = true;
  // HDF5: read into this volume's storage when it has the dataset's type and
  // shape (taken): a series of stages reads each one into the storage of the
  // one before last instead of fresh pages the kernel must zero (a third of
  // `track`'s time at 1220^3).
  AnyVolume* reuse = nullptr;
  // Only these slices (every format reads just them: a TIFF its pages, a raw
  // file its bytes, HDF5 a hyperslab), the origin moved to the first one.
  // Outside the file: InputError naming it.
  SliceRange slices;
};

// What a volume file holds, from its metadata and one slice: the voxels are
// not read (a 3.6 GB scan's shape before deciding how to read it).
struct VolumeInfo {
  Shape shape;
  DType dtype = DType::u16;
  Geometry geometry;
};
VolumeInfo read_volume_info(const std::string& spec, const ReadOptions& opt = {});

// `range` within a volume of `depth` slices (nz < 0 taken as to the last);
// InputError "WHERE: slices [A, B) are not within its DEPTH slices" otherwise.
SliceRange slices_within(SliceRange range, int64_t depth, const std::string& where);

struct WriteOptions {
  int compression = 0;  // HDF5 deflate level 0..9 (0 = none)
  bool progress = true;
};

enum class FileFormat { tiff, tiff_folder, raw, hdf5 };
FileFormat format_of(const std::string& spec, bool for_writing);

// `spec` is a path, or for HDF5 "file.h5:/dataset".
AnyVolume read_volume(const std::string& spec, const ReadOptions& opt = {});

// Reads and checks the element type: "FILE: holds float32, expected uint16".
template <class T>
Volume<T> read_volume_as(const std::string& spec, const ReadOptions& opt = {});

// A label volume (0 = void, 1.. = particles) from any tool: uint32 as is;
// uint8 and uint16 widened; signed and 64-bit integers (TIFF, HDF5: what
// Python's labelling functions write) checked to be 0..2^32-1; float32
// (Fiji/MorphoLibJ's 32-bit labels) checked to hold integers 0..2^24.
// InputError naming the file otherwise (e.g. a grey scan given as labels).
Volume<uint32_t> read_label_volume(const std::string& spec, const ReadOptions& opt = {});

void write_volume(const AnyVolume& v, const std::string& spec, const WriteOptions& opt = {});
template <class T>
void write_volume(const Volume<T>& v, const std::string& spec, const WriteOptions& opt = {});

// The one answer to "is this HDF5?": the file part of `spec` ("file.h5" or
// "file.h5:/dataset") ends in .h5, .hdf5, .hdf or .nxs (any case).
bool is_hdf5(const std::string& spec);

// Splits "file.h5:/path" into ("file.h5", "/path"); dataset empty if absent.
std::pair<std::string, std::string> split_dataset_spec(const std::string& spec);

// Count of NaN/Inf voxels and the linear index of the first one (-1 if none).
std::pair<int64_t, int64_t> count_nonfinite(const Volume<float>& v);

}  // namespace tg

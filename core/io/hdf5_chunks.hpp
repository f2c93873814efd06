// Chunks of a volume dataset compressed and decompressed on every core.
//
// Why: libhdf5 runs its filters (shuffle, deflate) on the calling thread,
// one chunk after another. A 1220^3 u32 label volume (gzip level 1 +
// shuffle, 124 MB on disk for 7.2 GB of labels) took ~23 s to read back
// and about as long to write, on one core of two, in `segment`, `measure`
// and in every stage of `track`.
//
// Method: HDF5's direct chunk I/O (H5Dwrite_chunk / H5Dread_chunk, 1.10.3
// and later) moves a chunk's stored (filtered) bytes; the filters are
// applied here with libdeflate, each chunk of a row of chunks on its own OpenMP
// thread, in the byte format of HDF5's own filters, so that any HDF5
// reader (h5py, h5dump, HDF5's own filter path) reads the result:
//   * shuffle (H5Z_FILTER_SHUFFLE, H5Zshuffle.c): the chunk's bytes in
//     planes, byte b of every element, then byte b + 1, ...;
//   * deflate (H5Z_FILTER_DEFLATE, H5Zdeflate.c): one zlib stream of the
//     (shuffled) chunk at the dataset's level.
// Edge chunks are stored whole (padded with 0, the fill value), as HDF5
// stores them. Every HDF5 call stays on the calling thread (the library is
// not thread-safe); only libdeflate and the copies run on threads. Output does
// not depend on the thread count (each chunk's bytes are its own).
//
// Datasets whose pipeline is exactly [deflate] or [shuffle, deflate] (what
// tomograin writes with compression > 0) take this path, and so do chunked
// datasets without any filter: their chunks are moved whole, where libhdf5
// would read a chunk into a slab of whole slices with one read per row of
// the chunk (a 256-voxel u16 row: 512 bytes a system call; reading a
// 1220^3 scan that way took ~6 s of system calls alone). Any other pipeline,
// and chunks stored with a filter skipped, go through libhdf5.
//
// Corrupt input: a stored chunk larger than a deflate bound for the chunk, or
// one that does not inflate to exactly the chunk's bytes, is an InputError
// naming the chunk (libhdf5 itself over-reads on some corrupt chunks: see
// hdf5.cpp check_chunk_sizes).
#pragma once
#include <hdf5.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace tg::h5chunks {

// The dataset's filters when this path can take them.
struct Pipeline {
  bool usable = false;   // no filter, [deflate] or [shuffle, deflate]
  bool deflate = false;  // false: chunks stored as they are
  bool shuffle = false;
  int level = 0;         // deflate level
};
Pipeline pipeline_of(hid_t dcpl);

// A chunked 3-D dataset: its extent and chunk, both (z, y, x), and the
// element size in bytes.
struct Layout {
  hsize_t dims[3] = {0, 0, 0};
  hsize_t chunk[3] = {0, 0, 0};
  size_t elem = 0;
};

// Writes slices [z0, z0 + nz) of the dataset from `slab` (nz whole slices,
// z then y then x): z0 must start a row of chunks and nz fill it (or reach
// the end of the dataset). `where` names the dataset in errors.
void write_rows(hid_t dset, const Layout& layout, const Pipeline& p, const void* slab, int64_t z0, int64_t nz,
                const std::string& where);

// Reads slices [z0, z0 + nz) of the dataset into `out` (nz whole slices),
// from the rows of chunks that hold them. Chunks never written read as 0.
// Returns false (nothing guaranteed in `out`) when a chunk was stored with
// a filter skipped: the caller then reads through libhdf5.
// `done` is told the slices read so far after each row of chunks.
bool read_rows(hid_t dset, const Layout& layout, const Pipeline& p, void* out, int64_t z0, int64_t nz,
               const std::string& where, const std::function<void(int64_t done)>& done = {});

}  // namespace tg::h5chunks

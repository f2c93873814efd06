#include "core/io/hdf5_chunks.hpp"

#include <libdeflate.h>
#include <omp.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include "core/errors.hpp"

namespace tg::h5chunks {
namespace {

// A row of chunks: the chunks at one z offset, in (y, x) order.
struct ChunkRow {
  int64_t cz, cy, cx, ny, nx, ncy, ncx;
  size_t elem;
  size_t chunk_bytes() const { return size_t(cz * cy * cx) * elem; }
  int64_t count() const { return ncy * ncx; }
  int64_t y0(int64_t c) const { return (c / ncx) * cy; }
  int64_t x0(int64_t c) const { return (c % ncx) * cx; }
};

ChunkRow chunk_row_of(const Layout& L) {
  ChunkRow r{int64_t(L.chunk[0]), int64_t(L.chunk[1]), int64_t(L.chunk[2]), int64_t(L.dims[1]), int64_t(L.dims[2]), 0, 0,
        L.elem};
  r.ncy = (r.ny + r.cy - 1) / r.cy;
  r.ncx = (r.nx + r.cx - 1) / r.cx;
  return r;
}

// HDF5's shuffle: byte b of element e of a chunk of n elements is stored
// at b * n + e. These move one row of `count` elements between a volume
// row (elements side by side) and the chunk's byte planes (from element
// e0), with no whole-chunk copy in between. The element size is a
// template argument for the usual ones (u16, u32, f32, u64): the byte loop
// then unrolls and vectorises; with a run-time size, the strided byte
// stores made the copies 18 % of reading five 1220^3 label stages.
template <size_t E>
void planes_to_row_e(const unsigned char* planes, size_t n, size_t e0, size_t count, unsigned char* row) {
  for (size_t i = 0; i < count; ++i)
    for (size_t b = 0; b < E; ++b) row[i * E + b] = planes[b * n + e0 + i];
}
template <size_t E>
void row_to_planes_e(const unsigned char* row, size_t n, size_t e0, size_t count, unsigned char* planes) {
  for (size_t b = 0; b < E; ++b)
    for (size_t i = 0; i < count; ++i) planes[b * n + e0 + i] = row[i * E + b];
}
void planes_to_row(const unsigned char* planes, size_t n, size_t elem, size_t e0, size_t count, unsigned char* row) {
  switch (elem) {
    case 1: std::memcpy(row, planes + e0, count); return;
    case 2: planes_to_row_e<2>(planes, n, e0, count, row); return;
    case 4: planes_to_row_e<4>(planes, n, e0, count, row); return;
    case 8: planes_to_row_e<8>(planes, n, e0, count, row); return;
    default:
      for (size_t i = 0; i < count; ++i)
        for (size_t b = 0; b < elem; ++b) row[i * elem + b] = planes[b * n + e0 + i];
  }
}
void row_to_planes(const unsigned char* row, size_t n, size_t elem, size_t e0, size_t count, unsigned char* planes) {
  switch (elem) {
    case 1: std::memcpy(planes + e0, row, count); return;
    case 2: row_to_planes_e<2>(row, n, e0, count, planes); return;
    case 4: row_to_planes_e<4>(row, n, e0, count, planes); return;
    case 8: row_to_planes_e<8>(row, n, e0, count, planes); return;
    default:
      for (size_t b = 0; b < elem; ++b)
        for (size_t i = 0; i < count; ++i) planes[b * n + e0 + i] = row[i * elem + b];
  }
}

// Per thread: one chunk-sized buffer, allocated once per call and left
// uninitialised (a zeroed vector per chunk row and thread was 16 MB of
// fresh pages, kernel page clearing, per row of 1220^3 u32 chunks), and a
// libdeflate (de)compressor. libdeflate writes and checks zlib's format,
// Adler-32 included, as zlib does; its Adler-32 and inflate are vectorised
// (zlib's Adler-32 alone was 14 % of reading five 1220^3 label stages).
struct Scratch {
  size_t bytes;
  int threads = omp_get_max_threads();
  std::unique_ptr<unsigned char[]> mem;
  std::vector<libdeflate_compressor*> comp;
  std::vector<libdeflate_decompressor*> decomp;
  // level >= 0: compressors at that level; -1: decompressors; codec false: neither.
  Scratch(size_t b, int level, bool codec, const std::string& where)
      : bytes(b), mem(new unsigned char[b * size_t(threads)]), comp(size_t(threads)), decomp(size_t(threads)) {
    for (int t = 0; t < threads && codec; ++t) {
      comp[size_t(t)] = level >= 0 ? libdeflate_alloc_compressor(level) : nullptr;
      decomp[size_t(t)] = level < 0 ? libdeflate_alloc_decompressor() : nullptr;
      if (!(level >= 0 ? static_cast<void*>(comp[size_t(t)]) : static_cast<void*>(decomp[size_t(t)])))
        throw ResourceError(where + ": cannot allocate a deflate (de)compressor");
    }
  }
  ~Scratch() {
    for (auto* c : comp) libdeflate_free_compressor(c);
    for (auto* d : decomp) libdeflate_free_decompressor(d);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  unsigned char* mine() const { return mem.get() + bytes * size_t(omp_get_thread_num()); }
  libdeflate_compressor* compressor() const { return comp[size_t(omp_get_thread_num())]; }
  libdeflate_decompressor* decompressor() const { return decomp[size_t(omp_get_thread_num())]; }
};

}  // namespace

Pipeline pipeline_of(hid_t dcpl) {
  Pipeline p;
  const int n = H5Pget_nfilters(dcpl);
  if (n < 0 || n > 2) return p;
  for (int i = 0; i < n; ++i) {
    unsigned flags = 0, cd[8] = {0};
    size_t ncd = 8;
    const H5Z_filter_t f = H5Pget_filter2(dcpl, unsigned(i), &flags, &ncd, cd, 0, nullptr, nullptr);
    if (n == 2 && i == 0) {
      if (f != H5Z_FILTER_SHUFFLE) return p;
      p.shuffle = true;
    } else {
      if (f != H5Z_FILTER_DEFLATE || ncd < 1 || cd[0] > 9) return p;
      p.deflate = true;
      p.level = int(cd[0]);
    }
  }
  p.usable = true;
  return p;
}

void write_rows(hid_t dset, const Layout& layout, const Pipeline& p, const void* slab, int64_t z0, int64_t nz,
                const std::string& where) {
  const ChunkRow R = chunk_row_of(layout);
  const int64_t depth = int64_t(layout.dims[0]);
  if (!p.usable || z0 < 0 || nz < 1 || z0 % R.cz != 0 || z0 + nz > depth || (nz % R.cz != 0 && z0 + nz != depth))
    throw UsageError(where + ": chunk rows must start and end on chunk boundaries");
  const size_t cbytes = R.chunk_bytes(), n = cbytes / R.elem;
  const auto* src = static_cast<const unsigned char*>(slab);
  const size_t slice_bytes = size_t(R.ny * R.nx) * R.elem;
  std::vector<std::vector<unsigned char>> stored(size_t(R.count()));
  const Scratch scratch(cbytes, p.level, p.deflate, where);
  for (int64_t zr = z0; zr < z0 + nz; zr += R.cz) {
    const int64_t rz = std::min(R.cz, z0 + nz - zr);
    int failed = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed)
    for (int64_t c = 0; c < R.count(); ++c) {
      const int64_t y0 = R.y0(c), x0 = R.x0(c);
      const int64_t wy = std::min(R.cy, R.ny - y0), wx = std::min(R.cx, R.nx - x0);
      unsigned char* const in = scratch.mine();  // the chunk as stored before deflate (shuffled or not)
      if (rz < R.cz || wy < R.cy || wx < R.cx) std::memset(in, 0, cbytes);  // edge chunk: fill value 0
      for (int64_t kz = 0; kz < rz; ++kz)
        for (int64_t jy = 0; jy < wy; ++jy) {
          const unsigned char* row = src + size_t(zr - z0 + kz) * slice_bytes + size_t((y0 + jy) * R.nx + x0) * R.elem;
          const size_t e0 = size_t((kz * R.cy + jy) * R.cx);
          if (p.shuffle)
            row_to_planes(row, n, R.elem, e0, size_t(wx), in);
          else
            std::memcpy(in + e0 * R.elem, row, size_t(wx) * R.elem);
        }
      auto& out = stored[size_t(c)];
      if (!p.deflate) {
        out.assign(in, in + cbytes);
        continue;
      }
      out.resize(libdeflate_zlib_compress_bound(scratch.compressor(), cbytes));
      const size_t len = libdeflate_zlib_compress(scratch.compressor(), in, cbytes, out.data(), out.size());
      if (len == 0) failed = 1;
      out.resize(len);
    }
    if (failed) throw ResourceError(where + ": libdeflate could not compress a chunk");
    for (int64_t c = 0; c < R.count(); ++c) {
      const hsize_t offset[3] = {hsize_t(zr), hsize_t(R.y0(c)), hsize_t(R.x0(c))};
      const auto& b = stored[size_t(c)];
      if (H5Dwrite_chunk(dset, H5P_DEFAULT, 0, offset, b.size(), b.data()) < 0)
        throw InputError(where + ": write failed");
    }
  }
}

bool read_rows(hid_t dset, const Layout& layout, const Pipeline& p, void* out_v, int64_t z0, int64_t nz,
               const std::string& where, const std::function<void(int64_t done)>& done) {
  const ChunkRow R = chunk_row_of(layout);
  const int64_t depth = int64_t(layout.dims[0]);
  if (!p.usable || z0 < 0 || nz < 1 || z0 + nz > depth) throw UsageError(where + ": slices outside the dataset");
  const size_t cbytes = R.chunk_bytes(), n = cbytes / R.elem;
  // A zlib stream of the chunk never needs much more than the chunk (stored
  // blocks add 5 bytes per 64 KiB, the wrapper 6; zlib's and libdeflate's
  // bounds are both under this); a larger stored chunk is corrupt, and must
  // not size a buffer.
  // Without a filter a chunk is stored as it is, exactly its bytes.
  const size_t most = p.deflate ? cbytes + cbytes / 64 + 1024 : cbytes;
  auto* out = static_cast<unsigned char*>(out_v);
  const size_t slice_bytes = size_t(R.ny * R.nx) * R.elem;
  // The stored chunks of a row: buffers of the largest size a chunk may
  // have, made once per call (when a chunk in their place is first found)
  // and left uninitialised (H5Dread_chunk fills them; a zero-filled vector
  // per chunk and row was a memset into fresh pages, ~12 % of measuring a
  // 1220^3 scan).
  std::vector<std::unique_ptr<unsigned char[]>> stored(size_t(R.count()));
  std::vector<size_t> stored_size(size_t(R.count()), 0);
  std::vector<char> present(size_t(R.count()));
  const Scratch scratch(cbytes, -1, p.deflate, where);
  for (int64_t zr = (z0 / R.cz) * R.cz; zr < z0 + nz; zr += R.cz) {
    // Stored bytes, read on this thread.
    for (int64_t c = 0; c < R.count(); ++c) {
      const hsize_t offset[3] = {hsize_t(zr), hsize_t(R.y0(c)), hsize_t(R.x0(c))};
      unsigned mask = 0;
      haddr_t addr = HADDR_UNDEF;
      hsize_t size = 0;
      if (H5Dget_chunk_info_by_coord(dset, offset, &mask, &addr, &size) < 0)
        throw InputError(where + ": corrupt chunk index (chunk at slice " + std::to_string(zr) + ")");
      present[size_t(c)] = addr != HADDR_UNDEF;
      if (!present[size_t(c)]) continue;
      if (size == 0 || size > most || (!p.deflate && size != cbytes))
        throw InputError(where + ": corrupt chunk at slice " + std::to_string(zr) + " (stored " +
                         std::to_string(size) + " bytes for a chunk of " + std::to_string(cbytes) + ")");
      if (!stored[size_t(c)]) stored[size_t(c)].reset(new unsigned char[most]);
      stored_size[size_t(c)] = size_t(size);
      uint32_t filters = 0;
      if (H5Dread_chunk(dset, H5P_DEFAULT, offset, &filters, stored[size_t(c)].get()) < 0)
        throw InputError(where + ": read failed (corrupt or truncated file?)");
      if (filters != 0) return false;  // a filter was skipped for this chunk: libhdf5 knows how
    }
    const int64_t k0 = std::max(zr, z0), k1 = std::min(zr + R.cz, z0 + nz);  // slices wanted from this row
    int64_t bad = -1;
#pragma omp parallel for schedule(dynamic, 1) reduction(max : bad)
    for (int64_t c = 0; c < R.count(); ++c) {
      const int64_t y0 = R.y0(c), x0 = R.x0(c);
      const int64_t wy = std::min(R.cy, R.ny - y0), wx = std::min(R.cx, R.nx - x0);
      // The inflated chunk (shuffled or not); without a filter, the stored bytes.
      unsigned char* const raw = p.deflate ? scratch.mine() : stored[size_t(c)].get();
      if (present[size_t(c)] && p.deflate) {
        size_t len = 0;
        if (libdeflate_zlib_decompress(scratch.decompressor(), stored[size_t(c)].get(), stored_size[size_t(c)], raw,
                                       cbytes, &len) != LIBDEFLATE_SUCCESS ||
            len != cbytes) {
          bad = std::max(bad, c);
          continue;
        }
      }
      for (int64_t k = k0; k < k1; ++k)
        for (int64_t jy = 0; jy < wy; ++jy) {
          unsigned char* row = out + size_t(k - z0) * slice_bytes + size_t((y0 + jy) * R.nx + x0) * R.elem;
          const size_t e0 = size_t(((k - zr) * R.cy + jy) * R.cx);
          if (!present[size_t(c)])
            std::memset(row, 0, size_t(wx) * R.elem);  // never written: the fill value
          else if (p.shuffle)
            planes_to_row(raw, n, R.elem, e0, size_t(wx), row);
          else
            std::memcpy(row, raw + e0 * R.elem, size_t(wx) * R.elem);
        }
    }
    if (bad >= 0)
      throw InputError(where + ": corrupt chunk at slice " + std::to_string(zr) + ", y " +
                       std::to_string(R.y0(bad)) + ", x " + std::to_string(R.x0(bad)) +
                       " (it does not inflate to the chunk's size)");
    if (done) done(std::min(zr + R.cz, z0 + nz) - z0);
  }
  return true;
}

}  // namespace tg::h5chunks

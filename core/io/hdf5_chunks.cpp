#include "core/io/hdf5_chunks.hpp"

#include <omp.h>
#include <zlib.h>

#include <algorithm>
#include <cstring>
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

// HDF5's shuffle: byte b of element e goes to b * n + e.
void shuffle_bytes(const unsigned char* in, unsigned char* out, size_t n, size_t elem) {
  for (size_t b = 0; b < elem; ++b)
    for (size_t e = 0; e < n; ++e) out[b * n + e] = in[e * elem + b];
}
void unshuffle_bytes(const unsigned char* in, unsigned char* out, size_t n, size_t elem) {
  for (size_t b = 0; b < elem; ++b)
    for (size_t e = 0; e < n; ++e) out[e * elem + b] = in[b * n + e];
}

}  // namespace

Pipeline pipeline_of(hid_t dcpl) {
  Pipeline p;
  const int n = H5Pget_nfilters(dcpl);
  if (n < 1 || n > 2) return p;
  for (int i = 0; i < n; ++i) {
    unsigned flags = 0, cd[8] = {0};
    size_t ncd = 8;
    const H5Z_filter_t f = H5Pget_filter2(dcpl, unsigned(i), &flags, &ncd, cd, 0, nullptr, nullptr);
    if (n == 2 && i == 0) {
      if (f != H5Z_FILTER_SHUFFLE) return p;
      p.shuffle = true;
    } else {
      if (f != H5Z_FILTER_DEFLATE || ncd < 1 || cd[0] > 9) return p;
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
  for (int64_t zr = z0; zr < z0 + nz; zr += R.cz) {
    const int64_t rz = std::min(R.cz, z0 + nz - zr);
    int failed = 0;
#pragma omp parallel reduction(| : failed)
    {
      std::vector<unsigned char> raw(cbytes), shuf(p.shuffle && R.elem > 1 ? cbytes : 0);
#pragma omp for schedule(dynamic, 1)
      for (int64_t c = 0; c < R.count(); ++c) {
        const int64_t y0 = R.y0(c), x0 = R.x0(c);
        const int64_t wy = std::min(R.cy, R.ny - y0), wx = std::min(R.cx, R.nx - x0);
        if (rz < R.cz || wy < R.cy || wx < R.cx) std::memset(raw.data(), 0, cbytes);  // edge chunk: fill value 0
        for (int64_t kz = 0; kz < rz; ++kz)
          for (int64_t jy = 0; jy < wy; ++jy)
            std::memcpy(raw.data() + size_t((kz * R.cy + jy) * R.cx) * R.elem,
                        src + size_t(zr - z0 + kz) * slice_bytes + size_t((y0 + jy) * R.nx + x0) * R.elem,
                        size_t(wx) * R.elem);
        const unsigned char* in = raw.data();
        if (!shuf.empty()) {
          shuffle_bytes(raw.data(), shuf.data(), n, R.elem);
          in = shuf.data();
        }
        auto& out = stored[size_t(c)];
        uLongf len = compressBound(uLong(cbytes));
        out.resize(len);
        if (compress2(out.data(), &len, in, uLong(cbytes), p.level) != Z_OK) failed = 1;
        out.resize(len);
      }
    }
    if (failed) throw ResourceError(where + ": zlib could not compress a chunk");
    for (int64_t c = 0; c < R.count(); ++c) {
      const hsize_t offset[3] = {hsize_t(zr), hsize_t(R.y0(c)), hsize_t(R.x0(c))};
      const auto& b = stored[size_t(c)];
      if (H5Dwrite_chunk(dset, H5P_DEFAULT, 0, offset, b.size(), b.data()) < 0)
        throw InputError(where + ": write failed");
    }
  }
}

bool read_rows(hid_t dset, const Layout& layout, const Pipeline& p, void* out_v, int64_t z0, int64_t nz,
               const std::string& where) {
  const ChunkRow R = chunk_row_of(layout);
  const int64_t depth = int64_t(layout.dims[0]);
  if (!p.usable || z0 < 0 || nz < 1 || z0 + nz > depth) throw UsageError(where + ": slices outside the dataset");
  const size_t cbytes = R.chunk_bytes(), n = cbytes / R.elem;
  // A deflate stream never needs more than zlib's bound (plus its header);
  // a larger stored chunk is corrupt, and must not size a buffer.
  const size_t most = size_t(compressBound(uLong(cbytes))) + 64;
  auto* out = static_cast<unsigned char*>(out_v);
  const size_t slice_bytes = size_t(R.ny * R.nx) * R.elem;
  std::vector<std::vector<unsigned char>> stored(size_t(R.count()));
  std::vector<char> present(size_t(R.count()));
  for (int64_t zr = (z0 / R.cz) * R.cz; zr < z0 + nz; zr += R.cz) {
    // Stored bytes, read on this thread.
    for (int64_t c = 0; c < R.count(); ++c) {
      const hsize_t offset[3] = {hsize_t(zr), hsize_t(R.y0(c)), hsize_t(R.x0(c))};
      unsigned mask = 0;
      haddr_t addr = HADDR_UNDEF;
      hsize_t size = 0;
      if (H5Dget_chunk_info_by_coord(dset, offset, &mask, &addr, &size) < 0)
        throw InputError(where + ": corrupt chunk index (chunk at slice " + std::to_string(zr) + ")");
      auto& b = stored[size_t(c)];
      present[size_t(c)] = addr != HADDR_UNDEF;
      if (!present[size_t(c)]) continue;
      if (size == 0 || size > most)
        throw InputError(where + ": corrupt chunk at slice " + std::to_string(zr) + " (stored " +
                         std::to_string(size) + " bytes for a chunk of " + std::to_string(cbytes) + ")");
      b.resize(size_t(size));
      uint32_t filters = 0;
      if (H5Dread_chunk(dset, H5P_DEFAULT, offset, &filters, b.data()) < 0)
        throw InputError(where + ": read failed (corrupt or truncated file?)");
      if (filters != 0) return false;  // a filter was skipped for this chunk: libhdf5 knows how
    }
    const int64_t k0 = std::max(zr, z0), k1 = std::min(zr + R.cz, z0 + nz);  // slices wanted from this row
    int64_t bad = -1;
#pragma omp parallel reduction(max : bad)
    {
      std::vector<unsigned char> raw(cbytes), plain(p.shuffle && R.elem > 1 ? cbytes : 0);
#pragma omp for schedule(dynamic, 1)
      for (int64_t c = 0; c < R.count(); ++c) {
        const int64_t y0 = R.y0(c), x0 = R.x0(c);
        const int64_t wy = std::min(R.cy, R.ny - y0), wx = std::min(R.cx, R.nx - x0);
        const unsigned char* data = raw.data();
        if (!present[size_t(c)]) {
          std::memset(raw.data(), 0, cbytes);
        } else {
          const auto& b = stored[size_t(c)];
          uLongf len = uLongf(cbytes);
          if (uncompress(raw.data(), &len, b.data(), uLong(b.size())) != Z_OK || len != cbytes) {
            bad = std::max(bad, c);
            continue;
          }
          if (!plain.empty()) {
            unshuffle_bytes(raw.data(), plain.data(), n, R.elem);
            data = plain.data();
          }
        }
        for (int64_t k = k0; k < k1; ++k)
          for (int64_t jy = 0; jy < wy; ++jy)
            std::memcpy(out + size_t(k - z0) * slice_bytes + size_t((y0 + jy) * R.nx + x0) * R.elem,
                        data + size_t(((k - zr) * R.cy + jy) * R.cx) * R.elem, size_t(wx) * R.elem);
      }
    }
    if (bad >= 0)
      throw InputError(where + ": corrupt chunk at slice " + std::to_string(zr) + ", y " +
                       std::to_string(R.y0(bad)) + ", x " + std::to_string(R.x0(bad)) +
                       " (it does not inflate to the chunk's size)");
  }
  return true;
}

}  // namespace tg::h5chunks

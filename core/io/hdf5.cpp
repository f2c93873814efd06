#include "core/io/hdf5.hpp"
#include "core/io/hdf5_chunks.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/progress.hpp"

namespace tg {
namespace fs = std::filesystem;

namespace {

// RAII for hid_t handles; the closer matches the object kind.
class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) { reset(); id_ = o.id_; close_ = o.close_; o.id_ = -1; }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  void reset() { if (id_ >= 0 && close_) close_(id_); id_ = -1; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

Handle file_h(hid_t id) { return {id, H5Fclose}; }
Handle dset_h(hid_t id) { return {id, H5Dclose}; }
Handle space_h(hid_t id) { return {id, H5Sclose}; }
Handle plist_h(hid_t id) { return {id, H5Pclose}; }
Handle type_h(hid_t id) { return {id, H5Tclose}; }
Handle attr_h(hid_t id) { return {id, H5Aclose}; }
Handle group_h(hid_t id) { return {id, H5Gclose}; }

hid_t native_of(DType t) {
  switch (t) {
    case DType::u8: return H5T_NATIVE_UINT8;
    case DType::u16: return H5T_NATIVE_UINT16;
    case DType::u32: return H5T_NATIVE_UINT32;
    case DType::f32: return H5T_NATIVE_FLOAT;
  }
  return H5T_NATIVE_UINT8;
}
template <class T> hid_t native_type() { return native_of(dtype_of<T>()); }

// Absolute dataset path. Built by append: GCC 12 warns falsely (-Wrestrict) on "/" + string.
std::string norm(const std::string& ds) {
  if (!ds.empty() && ds[0] == '/') return ds;
  std::string out(1, '/');
  out += ds;
  return out;
}

bool path_exists(hid_t file, const std::string& path) {
  // H5Lexists needs every parent to exist: walk the components.
  std::string cur;
  std::istringstream is(path);
  std::string part;
  while (std::getline(is, part, '/')) {
    if (part.empty()) continue;
    cur += "/" + part;
    if (H5Lexists(file, cur.c_str(), H5P_DEFAULT) <= 0) return false;
  }
  return !cur.empty();
}

void write_attr_doubles(hid_t obj, const char* name, const double* v, hsize_t n) {
  if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);  // the root copy is rewritten by every volume
  Handle sp = space_h(H5Screate_simple(1, &n, nullptr));
  Handle a = attr_h(H5Acreate2(obj, name, H5T_NATIVE_DOUBLE, sp.get(), H5P_DEFAULT, H5P_DEFAULT));
  H5Awrite(a.get(), H5T_NATIVE_DOUBLE, v);
}

void write_attr_string(hid_t obj, const char* name, const std::string& s) {
  Handle t = type_h(H5Tcopy(H5T_C_S1));
  H5Tset_size(t.get(), std::max<size_t>(1, s.size()));
  Handle sp = space_h(H5Screate(H5S_SCALAR));
  if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
  Handle a = attr_h(H5Acreate2(obj, name, t.get(), sp.get(), H5P_DEFAULT, H5P_DEFAULT));
  std::string buf = s.empty() ? std::string(1, '\0') : s;
  H5Awrite(a.get(), t.get(), buf.data());
}

bool read_attr_doubles(hid_t obj, const char* name, double* v, size_t n) {
  if (H5Aexists(obj, name) <= 0) return false;
  Handle a = attr_h(H5Aopen(obj, name, H5P_DEFAULT));
  Handle sp = space_h(H5Aget_space(a.get()));
  if (H5Sget_simple_extent_npoints(sp.get()) != static_cast<hssize_t>(n)) return false;
  return H5Aread(a.get(), H5T_NATIVE_DOUBLE, v) >= 0;
}

// voxel_size_m as 3 doubles (z, y, x) or one (isotropic; the usual h5py idiom
// `f.attrs["voxel_size_m"] = 12.3e-6`); any other count is an error, not "no
// size". Without it, element_size_um (z, y, x) in micrometres, as Fiji's HDF5
// plugin writes it (other counts of that one: no size).
bool read_voxel_size(hid_t obj, const std::string& where, double* v) {
  const bool si = H5Aexists(obj, "voxel_size_m") > 0;
  if (!si && H5Aexists(obj, "element_size_um") <= 0) return false;
  const char* name = si ? "voxel_size_m" : "element_size_um";
  Handle a = attr_h(H5Aopen(obj, name, H5P_DEFAULT));
  Handle sp = space_h(H5Aget_space(a.get()));
  const hssize_t n = H5Sget_simple_extent_npoints(sp.get());
  if (!si && n != 1 && n != 3) return false;  // another tool's axes (a channel's too): no size, not an error
  if (n != 1 && n != 3)
    throw InputError(where + ": attribute " + name + " holds " + std::to_string(n) + " values, expected 1 or 3 (z, y, x)");
  if (H5Aread(a.get(), H5T_NATIVE_DOUBLE, v) < 0) throw InputError(where + ": attribute " + name + " is not numeric");
  if (n == 1) v[1] = v[2] = v[0];
  if (!si)
    for (int k = 0; k < 3; ++k) v[k] *= 1e-6;
  return true;
}

std::string read_attr_string(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return "";
  Handle a = attr_h(H5Aopen(obj, name, H5P_DEFAULT));
  Handle ft = type_h(H5Aget_type(a.get()));
  if (H5Tget_class(ft.get()) != H5T_STRING) return "";
  if (H5Tis_variable_str(ft.get()) > 0) {
    char* s = nullptr;
    Handle mt = type_h(H5Tcopy(H5T_C_S1));
    H5Tset_size(mt.get(), H5T_VARIABLE);
    if (H5Aread(a.get(), mt.get(), &s) < 0 || !s) return "";
    std::string out(s);
    H5free_memory(s);
    return out;
  }
  const size_t n = H5Tget_size(ft.get());
  std::string buf(n, '\0');
  H5Aread(a.get(), ft.get(), buf.data());
  return std::string(buf.c_str());
}

// libhdf5 1.10.8 trusts a chunked layout whose chunk exceeds a fixed maximum
// extent of the dataset (H5Pset_chunk refuses such a layout, so only a
// corrupt file has one) and then copies past its buffers inside H5Dread
// (found by fuzzing: tests/fuzz/regressions/hdf5/libhdf5-chunk-beyond-extent.h5).
// It also reads an unfiltered chunk whose stored size is smaller than the
// chunk as if it were whole (heap over-read in H5VM_memcpyvv, found by
// fuzzing: tests/fuzz/known/hdf5/libhdf5-short-chunk-read-overflow.h5), so
// each stored chunk's size is compared with the chunk's when there are no
// filters. H5Dget_chunk_info walks the chunk index for each call, so this
// is done for files of up to kMaxCheckedChunks chunks (ours have one chunk
// per 16 slices; a 1220^3 scan has 77).
// Checked before every read through libhdf5. A 3-D dataset read by
// hdf5_chunks (unfiltered, or deflate with or without shuffle) is not walked
// here: that path checks each chunk's stored size as it reads it, and the
// walk costs O(chunks^2) per call (a 1220^3 scan in 16 x 256 x 256 chunks
// has 1925: reading it in 14 slabs spent ~5 s in the walk).
constexpr hsize_t kMaxCheckedChunks = 4096;

void check_chunk_sizes(hid_t dset, hid_t dcpl, hid_t space, const std::vector<hsize_t>& chunk, const std::string& where) {
  if (H5Pget_nfilters(dcpl) != 0) return;  // compressed chunks have any stored size
  Handle ft = type_h(H5Dget_type(dset));
  hsize_t bytes = ft.ok() ? H5Tget_size(ft.get()) : 0;
  for (hsize_t c : chunk) bytes *= c;
  hsize_t n = 0;
  if (H5Dget_num_chunks(dset, space, &n) < 0 || n > kMaxCheckedChunks) return;
  for (hsize_t i = 0; i < n; ++i) {
    unsigned mask = 0;
    haddr_t addr = 0;
    hsize_t size = 0;
    if (H5Dget_chunk_info(dset, space, i, nullptr, &mask, &addr, &size) < 0)
      throw InputError(where + ": corrupt chunk index (chunk " + std::to_string(i) + " cannot be read)");
    if (size != bytes)
      throw InputError(where + ": corrupt chunk " + std::to_string(i) + " (stored " + std::to_string(size) +
                       " bytes, an uncompressed chunk has " + std::to_string(bytes) + ")");
  }
}

void check_chunk_layout(hid_t dset, hid_t space, const std::string& where, bool sizes = true) {
  Handle dcpl = plist_h(H5Dget_create_plist(dset));
  if (!dcpl.ok() || H5Pget_layout(dcpl.get()) != H5D_CHUNKED) return;
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1 || rank > 32) throw InputError(where + ": corrupt dataspace (rank " + std::to_string(rank) + ")");
  std::vector<hsize_t> chunk(static_cast<size_t>(rank)), maxd(static_cast<size_t>(rank));
  if (H5Pget_chunk(dcpl.get(), rank, chunk.data()) != rank || H5Sget_simple_extent_dims(space, nullptr, maxd.data()) != rank)
    throw InputError(where + ": corrupt chunk layout (chunk rank differs from the dataset's)");
  for (size_t r = 0; r < chunk.size(); ++r)
    if (chunk[r] == 0 || (maxd[r] != H5S_UNLIMITED && chunk[r] > maxd[r]))
      throw InputError(where + ": corrupt chunk layout (chunk dimension " + std::to_string(chunk[r]) +
                       " exceeds the dataset's maximum " + std::to_string(maxd[r]) + ")");
  if (sizes) check_chunk_sizes(dset, dcpl.get(), space, chunk, where);
}

// HDF5 prints its error stack to stderr by default; our errors are one line,
// so switch the printer off once, before the first call into the library.
void quiet_hdf5() {
  static const bool once = [] { return H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr) >= 0; }();
  (void)once;
}

hid_t lcpl_intermediate() {
  hid_t p = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(p, 1);
  return p;
}

}  // namespace

// ------------------------------------------------------------------ writer
struct H5Writer::Impl {
  std::string path;
  AtomicPath out;
  Handle file;
  explicit Impl(const std::string& p) : path(p), out(p) {}
};

H5Writer::H5Writer(const std::string& path) : impl_(std::make_unique<Impl>(path)) {
  quiet_hdf5();
  impl_->file = file_h(H5Fcreate(impl_->out.temp().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  if (!impl_->file.ok()) throw InputError(path + ": cannot create HDF5 file");
}

H5Writer::~H5Writer() = default;

void H5Writer::create_volume(const std::string& dataset, DType type, const Shape& s, const Geometry& g,
                             int compression) {
  const std::string ds = norm(dataset);
  if (s.empty()) throw UsageError(impl_->path + ":" + ds + ": cannot store an empty volume " + s.str());
  if (compression < 0 || compression > 9) throw UsageError("HDF5 compression level must be 0..9");
  const hsize_t dims[3] = {static_cast<hsize_t>(s.nz), static_cast<hsize_t>(s.ny), static_cast<hsize_t>(s.nx)};
  // Chunks of up to 16 slices x 256 x 256: small enough for partial reads, large for throughput.
  const hsize_t chunk[3] = {std::min<hsize_t>(dims[0], 16), std::min<hsize_t>(dims[1], 256),
                            std::min<hsize_t>(dims[2], 256)};
  Handle space = space_h(H5Screate_simple(3, dims, nullptr));
  Handle dcpl = plist_h(H5Pcreate(H5P_DATASET_CREATE));
  H5Pset_chunk(dcpl.get(), 3, chunk);
  if (compression > 0) {
    H5Pset_shuffle(dcpl.get());
    H5Pset_deflate(dcpl.get(), static_cast<unsigned>(compression));
  }
  const hid_t ftype = native_of(type);
  Handle lcpl = plist_h(lcpl_intermediate());
  Handle d = dset_h(H5Dcreate2(impl_->file.get(), ds.c_str(), ftype, space.get(), lcpl.get(), dcpl.get(), H5P_DEFAULT));
  if (!d.ok()) throw InputError(impl_->path + ":" + ds + ": cannot create dataset");
  write_attr_doubles(d.get(), "voxel_size_m", g.voxel_size_m.data(), 3);
  write_attr_doubles(d.get(), "origin_m", g.origin_m.data(), 3);
  write_attr_string(d.get(), "units", "voxel_size_m and origin_m in metres, (z, y, x) order");
  // Same geometry on the root, so tools that look at the file see it too.
  write_attr_doubles(impl_->file.get(), "voxel_size_m", g.voxel_size_m.data(), 3);
  write_attr_doubles(impl_->file.get(), "origin_m", g.origin_m.data(), 3);
}

template <class T>
void H5Writer::write_slab(const std::string& dataset, int64_t z0, const Volume<T>& v, int64_t vz0, int64_t nz) {
  const std::string ds = norm(dataset);
  Handle d = dset_h(H5Dopen2(impl_->file.get(), ds.c_str(), H5P_DEFAULT));
  if (!d.ok()) throw UsageError(impl_->path + ":" + ds + ": write_slab before create_volume");
  Handle fsp = space_h(H5Dget_space(d.get()));
  hsize_t dims[3] = {0, 0, 0};
  if (H5Sget_simple_extent_ndims(fsp.get()) != 3) throw UsageError(impl_->path + ":" + ds + ": not a volume");
  H5Sget_simple_extent_dims(fsp.get(), dims, nullptr);
  const Shape& s = v.shape();
  if (nz <= 0 || vz0 < 0 || vz0 + nz > s.nz || z0 < 0 || hsize_t(z0 + nz) > dims[0] || hsize_t(s.ny) != dims[1] ||
      hsize_t(s.nx) != dims[2])
    throw UsageError(impl_->path + ":" + ds + ": slab of " + std::to_string(nz) + " slices at " + std::to_string(z0) +
                     " does not fit the dataset");
  // Compressed chunks are filtered here on every core (hdf5_chunks.hpp)
  // when the slab is whole rows of chunks, as write_volume's are.
  Handle dcpl = plist_h(H5Dget_create_plist(d.get()));
  h5chunks::Layout layout{{dims[0], dims[1], dims[2]}, {0, 0, 0}, sizeof(T)};
  Handle ft = type_h(H5Dget_type(d.get()));  // the stored bytes must be T's own (not a big-endian dataset)
  if (dcpl.ok() && H5Pget_layout(dcpl.get()) == H5D_CHUNKED && H5Pget_chunk(dcpl.get(), 3, layout.chunk) == 3 &&
      H5Tequal(ft.get(), native_type<T>()) > 0) {
    const h5chunks::Pipeline pipe = h5chunks::pipeline_of(dcpl.get());
    const int64_t cz = int64_t(layout.chunk[0]);
    if (pipe.usable && z0 % cz == 0 && (nz % cz == 0 || hsize_t(z0 + nz) == dims[0])) {
      h5chunks::write_rows(d.get(), layout, pipe, v.data() + vz0 * s.slice_voxels(), z0, nz, impl_->path + ":" + ds);
      return;
    }
  }
  const hsize_t start[3] = {hsize_t(z0), 0, 0}, count[3] = {hsize_t(nz), dims[1], dims[2]};
  H5Sselect_hyperslab(fsp.get(), H5S_SELECT_SET, start, nullptr, count, nullptr);
  Handle msp = space_h(H5Screate_simple(3, count, nullptr));
  if (H5Dwrite(d.get(), native_type<T>(), msp.get(), fsp.get(), H5P_DEFAULT, v.data() + vz0 * s.slice_voxels()) < 0)
    throw InputError(impl_->path + ":" + ds + ": write failed");
}

template <class T>
void H5Writer::write_volume(const std::string& dataset, const Volume<T>& v, int compression) {
  const auto& s = v.shape();
  create_volume(dataset, dtype_of<T>(), s, v.geometry(), compression);
  // Write in slabs of whole chunk rows so progress can be shown and the chunk cache stays small.
  Progress bar("writing " + fs::path(impl_->path).filename().string() + norm(dataset), static_cast<double>(s.nz));
  constexpr int64_t kChunkSlices = 16;
  for (int64_t z0 = 0; z0 < s.nz; z0 += kChunkSlices) {
    const int64_t nz = std::min(kChunkSlices, s.nz - z0);
    write_slab(dataset, z0, v, z0, nz);
    bar.update(static_cast<double>(z0 + nz));
  }
}

void H5Writer::write_volume(const std::string& dataset, const AnyVolume& v, int compression) {
  std::visit([&](const auto& vol) { write_volume(dataset, vol, compression); }, v);
}

void H5Writer::write_table(const std::string& group, const Table& t) {
  const std::string g = norm(group);
  Handle lcpl = plist_h(lcpl_intermediate());
  Handle grp = group_h(H5Gcreate2(impl_->file.get(), g.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!grp.ok()) throw InputError(impl_->path + ":" + g + ": cannot create table group");
  std::string names;
  for (const auto& c : t.columns()) {
    names += (names.empty() ? "" : ",") + c.name;
    const hsize_t n = static_cast<hsize_t>(c.size());
    Handle sp = space_h(H5Screate_simple(1, &n, nullptr));
    if (!c.is_text) {
      Handle d = dset_h(H5Dcreate2(grp.get(), c.name.c_str(), H5T_NATIVE_DOUBLE, sp.get(), H5P_DEFAULT, H5P_DEFAULT,
                                   H5P_DEFAULT));
      if (!d.ok() || (n > 0 && H5Dwrite(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, c.num.data()) < 0))
        throw InputError(impl_->path + ":" + g + "/" + c.name + ": write failed");
    } else {
      size_t w = 1;
      for (const auto& s : c.text) w = std::max(w, s.size());
      std::vector<char> buf(w * std::max<size_t>(1, c.text.size()), '\0');
      for (size_t r = 0; r < c.text.size(); ++r) std::memcpy(buf.data() + r * w, c.text[r].data(), c.text[r].size());
      Handle st = type_h(H5Tcopy(H5T_C_S1));
      H5Tset_size(st.get(), w);
      Handle d = dset_h(H5Dcreate2(grp.get(), c.name.c_str(), st.get(), sp.get(), H5P_DEFAULT, H5P_DEFAULT,
                                   H5P_DEFAULT));
      if (!d.ok() || (n > 0 && H5Dwrite(d.get(), st.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0))
        throw InputError(impl_->path + ":" + g + "/" + c.name + ": write failed");
    }
  }
  write_attr_string(grp.get(), "columns", names);
}

void H5Writer::write_attribute(const std::string& name, const std::string& value) {
  write_attr_string(impl_->file.get(), name.c_str(), value);
}

void H5Writer::commit() {
  if (H5Fflush(impl_->file.get(), H5F_SCOPE_GLOBAL) < 0) throw InputError(impl_->path + ": flush failed");
  impl_->file.reset();
  impl_->out.commit();
}

template void H5Writer::write_volume(const std::string&, const Volume<uint8_t>&, int);
template void H5Writer::write_volume(const std::string&, const Volume<uint16_t>&, int);
template void H5Writer::write_volume(const std::string&, const Volume<uint32_t>&, int);
template void H5Writer::write_volume(const std::string&, const Volume<float>&, int);
template void H5Writer::write_slab(const std::string&, int64_t, const Volume<uint8_t>&, int64_t, int64_t);
template void H5Writer::write_slab(const std::string&, int64_t, const Volume<uint16_t>&, int64_t, int64_t);
template void H5Writer::write_slab(const std::string&, int64_t, const Volume<uint32_t>&, int64_t, int64_t);
template void H5Writer::write_slab(const std::string&, int64_t, const Volume<float>&, int64_t, int64_t);

// ------------------------------------------------------------------ reader
struct H5Reader::Impl {
  std::string path;
  Handle file;
};

H5Reader::H5Reader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  impl_->path = path;
  if (!fs::is_regular_file(path)) throw InputError(path + ": no such file");
  if (H5Fis_hdf5(path.c_str()) <= 0) throw InputError(path + ": not an HDF5 file");
  impl_->file = file_h(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!impl_->file.ok()) throw InputError(path + ": cannot open HDF5 file (corrupt or truncated?)");
}

H5Reader::~H5Reader() = default;

bool H5Reader::has(const std::string& dataset) const { return path_exists(impl_->file.get(), norm(dataset)); }

std::vector<std::string> H5Reader::datasets() const {
  std::vector<std::string> out;
  auto cb = [](hid_t, const char* name, const H5O_info_t* info, void* data) -> herr_t {
    if (info->type == H5O_TYPE_DATASET) static_cast<std::vector<std::string>*>(data)->push_back(norm(name));
    return 0;
  };
  H5Ovisit2(impl_->file.get(), H5_INDEX_NAME, H5_ITER_NATIVE, cb, &out, H5O_INFO_BASIC);  // HDF5 1.10 API
  return out;
}

namespace {

// A volume's (z, y, x) in a dataset's dimensions: rank 3, one slice (rank
// 2), or up to 5 dimensions whose extra ones are 1, in front or behind
// (ilastik exports (z, y, x, c), some viewers (t, z, y, x)): z is dimension
// `lead` (-1 for a single slice of rank 2).
struct VolumeAxes {
  hsize_t zyx[3] = {1, 1, 1};
  int rank = 3;
  int lead = 0;
};
VolumeAxes volume_axes(const std::vector<hsize_t>& d, const std::string& where) {
  VolumeAxes a;
  a.rank = int(d.size());
  auto dims_str = [&] {
    std::string t;
    for (const hsize_t v : d) t += (t.empty() ? "" : ", ") + std::to_string(v);
    return "(" + t + ")";
  };
  if (a.rank == 2) {
    a.lead = -1, a.zyx[1] = d[0], a.zyx[2] = d[1];
    return a;
  }
  int lo = 0, hi = a.rank;  // [lo, hi): the dimensions left
  while (hi - lo > 3 && d[size_t(lo)] == 1) ++lo;
  while (hi - lo > 3 && d[size_t(hi - 1)] == 1) --hi;
  if (a.rank < 2 || a.rank > 5 || hi - lo != 3)
    throw InputError(where + ": dataset has dimensions " + dims_str() +
                     ", expected (z, y, x) (a single slice (y, x), or extra dimensions of 1 around them)");
  a.lead = lo;
  for (int k = 0; k < 3; ++k) a.zyx[k] = d[size_t(lo + k)];
  return a;
}

// Slices [z0, z0 + nz) of a dataset (nz < 0: all of them).
AnyVolume read_range(hid_t file, const std::string& path, const std::string& dataset, int64_t z0, int64_t nz,
                     bool progress, AnyVolume* reuse = nullptr) {
  const std::string ds = norm(dataset);
  const std::string where = path + ":" + ds;
  Handle d = dset_h(H5Dopen2(file, ds.c_str(), H5P_DEFAULT));
  if (!d.ok()) throw InputError(where + ": not a dataset");
  Handle ft = type_h(H5Dget_type(d.get()));
  const H5T_class_t cls = H5Tget_class(ft.get());
  const size_t size = H5Tget_size(ft.get());
  DType dt;
  bool labels_only = false;
  if (cls == H5T_INTEGER && H5Tget_sign(ft.get()) == H5T_SGN_NONE && size == 1) dt = DType::u8;
  else if (cls == H5T_INTEGER && H5Tget_sign(ft.get()) == H5T_SGN_NONE && size == 2) dt = DType::u16;
  else if (cls == H5T_INTEGER && H5Tget_sign(ft.get()) == H5T_SGN_NONE && size == 4) dt = DType::u32;
  else if (cls == H5T_FLOAT && size == 4) dt = DType::f32;
  // Signed or 64-bit integers (labels from Python: int32, int64): into
  // uint32 by libhdf5's conversion, refused when a value is out of range.
  else if (cls == H5T_INTEGER && (size == 1 || size == 2 || size == 4 || size == 8)) dt = DType::u32, labels_only = true;
  else throw InputError(where + ": element type is not uint8/uint16/uint32/float32 (or an integer label type)");
  Handle sp = space_h(H5Dget_space(d.get()));
  const int rank = H5Sget_simple_extent_ndims(sp.get());
  check_chunk_layout(d.get(), sp.get(), where, false);  // the chunk sizes below, where libhdf5 reads
  std::vector<hsize_t> all(size_t(std::max(0, rank)));
  H5Sget_simple_extent_dims(sp.get(), all.data(), nullptr);
  const VolumeAxes axes = volume_axes(all, where);
  const hsize_t* dims = axes.zyx;
  const Shape whole{static_cast<int64_t>(dims[0]), static_cast<int64_t>(dims[1]), static_cast<int64_t>(dims[2])};
  if (whole.empty()) throw InputError(where + ": dataset is empty " + whole.str());
  if (nz < 0) z0 = 0, nz = whole.nz;
  if (z0 < 0 || nz < 1 || z0 + nz > whole.nz)
    throw InputError(where + ": slices " + std::to_string(z0) + ".." + std::to_string(z0 + nz - 1) +
                     " are outside the dataset " + whole.str());
  const Shape shape{nz, whole.ny, whole.nx};
  Geometry g;
  double buf[3];
  if (read_voxel_size(d.get(), where, buf) || read_voxel_size(file, where, buf))
    g.voxel_size_m = {buf[0], buf[1], buf[2]};
  if (read_attr_doubles(d.get(), "origin_m", buf, 3)) g.origin_m = {buf[0], buf[1], buf[2]};
  for (double v : g.voxel_size_m)
    if (!(v >= 0 && std::isfinite(v))) throw InputError(where + ": attribute voxel_size_m (or element_size_um) is invalid");
  g.origin_m[0] += double(z0) * g.voxel_size_m[0];
  // Into `reuse`'s storage when it has this type and shape: its pages are
  // the process's already, none for the kernel to zero.
  const bool fits = reuse && dtype_of(*reuse) == dt && std::visit([&](const auto& v) { return v.shape() == shape; }, *reuse);
  AnyVolume out = fits ? std::move(*reuse) : make_volume(dt, shape, g);
  if (fits) std::visit([&](auto& v) { v.set_geometry(g); }, out);
  // Compressed chunks of a 3-D dataset are inflated on every core
  // (hdf5_chunks.hpp); any other layout or pipeline goes through libhdf5.
  h5chunks::Pipeline pipe;
  h5chunks::Layout layout;
  // The chunk path moves the stored bytes as they are: only where the stored
  // type is this machine's own (a big-endian dataset goes through libhdf5's
  // conversion, or its values would be read byte-swapped).
  if (rank == 3 && !labels_only && H5Tequal(ft.get(), native_of(dt)) > 0) {
    Handle dcpl = plist_h(H5Dget_create_plist(d.get()));
    if (dcpl.ok() && H5Pget_layout(dcpl.get()) == H5D_CHUNKED && H5Pget_chunk(dcpl.get(), 3, layout.chunk) == 3) {
      pipe = h5chunks::pipeline_of(dcpl.get());
      std::copy(dims, dims + 3, layout.dims);
      layout.elem = size_t(dtype_bytes(dt));
    }
  }
  if (!pipe.usable) check_chunk_layout(d.get(), sp.get(), where);
  std::visit(
      [&](auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        Progress bar("reading " + fs::path(path).filename().string() + ds, static_cast<double>(shape.nz));
        if (pipe.usable) {
          // Row of chunks by row of chunks (the first and last perhaps in part).
          if (h5chunks::read_rows(d.get(), layout, pipe, v.data(), z0, shape.nz, where, [&](int64_t done) {
                if (progress) bar.update(static_cast<double>(done));
              }))
            return;
        }
        // A value out of uint32's range stops the conversion (libhdf5 would clip it).
        Handle dxpl = plist_h(H5Pcreate(H5P_DATASET_XFER));
        if (labels_only)
          H5Pset_type_conv_cb(
              dxpl.get(),
              [](H5T_conv_except_t e, hid_t, hid_t, void*, void*, void*) {
                return e == H5T_CONV_EXCEPT_RANGE_HI || e == H5T_CONV_EXCEPT_RANGE_LOW ? H5T_CONV_ABORT
                                                                                        : H5T_CONV_UNHANDLED;
              },
              nullptr);
        const hsize_t step = 16;
        for (hsize_t k0 = 0; k0 < static_cast<hsize_t>(shape.nz); k0 += step) {
          hsize_t count[3] = {std::min<hsize_t>(step, shape.nz - k0), dims[1], dims[2]};
          Handle fsp = space_h(H5Dget_space(d.get()));
          if (axes.lead >= 0) {  // z at dimension lead; the dimensions of 1 around it: index 0
            std::vector<hsize_t> fstart(size_t(rank), 0), fcount(size_t(rank), 1);
            fstart[size_t(axes.lead)] = hsize_t(z0) + k0;
            for (int a = 0; a < 3; ++a) fcount[size_t(axes.lead + a)] = count[a];
            H5Sselect_hyperslab(fsp.get(), H5S_SELECT_SET, fstart.data(), nullptr, fcount.data(), nullptr);
          }
          Handle msp = space_h(H5Screate_simple(3, count, nullptr));
          if (H5Dread(d.get(), native_type<T>(), msp.get(), fsp.get(), dxpl.get(),
                      v.data() + static_cast<int64_t>(k0) * shape.slice_voxels()) < 0)
            throw InputError(where + (labels_only ? ": a value outside 0..4294967295 (a signed or 64-bit integer "
                                                    "dataset is read as labels only), or a corrupt file"
                                                  : ": read failed (corrupt or truncated file?)"));
          if (progress) bar.update(static_cast<double>(k0 + count[0]));
        }
      },
      out);
  return out;
}

}  // namespace

AnyVolume H5Reader::read_volume(const std::string& dataset, bool progress, AnyVolume* reuse) const {
  const std::string ds = norm(dataset);
  if (!has(ds)) {
    std::string avail;
    for (const auto& d : datasets()) avail += (avail.empty() ? "" : ", ") + d;
    throw InputError(impl_->path + ":" + ds + ": no such dataset" + (avail.empty() ? "" : " (file has: " + avail + ")"));
  }
  return read_range(impl_->file.get(), impl_->path, ds, 0, -1, progress, reuse);
}

AnyVolume H5Reader::read_slab(const std::string& dataset, int64_t z0, int64_t nz, AnyVolume* reuse) const {
  const std::string ds = norm(dataset);
  if (!has(ds)) throw InputError(impl_->path + ":" + ds + ": no such dataset");
  return read_range(impl_->file.get(), impl_->path, ds, z0, nz, false, reuse);
}

namespace {
// The extent of a dataset known to exist, one entry per dimension.
std::vector<hsize_t> dataset_dims(hid_t file, const std::string& ds, const std::string& where) {
  Handle d = dset_h(H5Dopen2(file, ds.c_str(), H5P_DEFAULT));
  if (!d.ok()) throw InputError(where + ": not a dataset");
  Handle sp = space_h(H5Dget_space(d.get()));
  std::vector<hsize_t> dims(size_t(std::max(0, H5Sget_simple_extent_ndims(sp.get()))));
  H5Sget_simple_extent_dims(sp.get(), dims.data(), nullptr);
  return dims;
}
}  // namespace

Shape H5Reader::shape(const std::string& dataset) const {
  const std::string ds = norm(dataset);
  const std::string where = impl_->path + ":" + ds;
  if (!has(ds)) throw InputError(where + ": no such dataset");
  const VolumeAxes a = volume_axes(dataset_dims(impl_->file.get(), ds, where), where);
  return Shape{static_cast<int64_t>(a.zyx[0]), static_cast<int64_t>(a.zyx[1]), static_cast<int64_t>(a.zyx[2])};
}

int H5Reader::rank(const std::string& dataset) const {
  const std::string ds = norm(dataset);
  const std::string where = impl_->path + ":" + ds;
  if (!has(ds)) throw InputError(where + ": no such dataset");
  return static_cast<int>(dataset_dims(impl_->file.get(), ds, where).size());
}

Table H5Reader::read_table(const std::string& group) const {
  const std::string g = norm(group);
  const std::string where = impl_->path + ":" + g;
  if (!has(g)) throw InputError(where + ": no such table");
  Handle grp = group_h(H5Gopen2(impl_->file.get(), g.c_str(), H5P_DEFAULT));
  if (!grp.ok()) throw InputError(where + ": not a table group");
  std::vector<std::string> names;
  {
    std::istringstream is(read_attr_string(grp.get(), "columns"));
    std::string n;
    while (std::getline(is, n, ',')) names.push_back(n);
  }
  Table t;
  t.source = where;
  for (const auto& n : names) {
    Handle d = dset_h(H5Dopen2(grp.get(), n.c_str(), H5P_DEFAULT));
    if (!d.ok()) throw InputError(where + ": column '" + n + "' missing");
    Handle sp = space_h(H5Dget_space(d.get()));
    if (H5Sget_simple_extent_ndims(sp.get()) != 1) throw InputError(where + "/" + n + ": column is not 1-D");
    check_chunk_layout(d.get(), sp.get(), where + "/" + n);
    const hssize_t rows = H5Sget_simple_extent_npoints(sp.get());
    check_allocation(rows * 8, where + "/" + n);
    Handle ft = type_h(H5Dget_type(d.get()));
    if (H5Tget_class(ft.get()) == H5T_STRING) {
      const size_t w = H5Tget_size(ft.get());
      if (H5Tis_variable_str(ft.get()) > 0 || w == 0) throw InputError(where + "/" + n + ": unsupported string column");
      std::vector<char> buf(w * static_cast<size_t>(std::max<hssize_t>(1, rows)));
      if (rows > 0 && H5Dread(d.get(), ft.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0)
        throw InputError(where + "/" + n + ": read failed");
      std::vector<std::string> col(static_cast<size_t>(rows));
      for (hssize_t r = 0; r < rows; ++r) col[r] = std::string(buf.data() + r * w, strnlen(buf.data() + r * w, w));
      t.add_text(n, std::move(col));
    } else {
      std::vector<double> col(static_cast<size_t>(rows));
      if (rows > 0 && H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, col.data()) < 0)
        throw InputError(where + "/" + n + ": read failed");
      t.add(n, std::move(col));
    }
  }
  return t;
}

std::string H5Reader::read_attribute(const std::string& name) const {
  return read_attr_string(impl_->file.get(), name.c_str());
}

}  // namespace tg

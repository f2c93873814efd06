#include "core/io/volume_io.hpp"

#include <cmath>
#include <filesystem>

#include "core/io/hdf5.hpp"
#include "core/io/raw.hpp"
#include "core/io/tiff.hpp"

namespace tg {
namespace fs = std::filesystem;

namespace {
std::string lower_ext(const std::string& p) {
  std::string e = fs::path(p).extension().string();
  for (auto& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}
bool is_h5_ext(const std::string& e) { return e == ".h5" || e == ".hdf5" || e == ".hdf" || e == ".nxs"; }
}  // namespace

std::pair<std::string, std::string> split_dataset_spec(const std::string& spec) {
  // "file.h5:/path" -> split at the last ':' that follows an HDF5 extension.
  for (const char* ext : {".h5:", ".hdf5:", ".hdf:", ".nxs:", ".H5:", ".HDF5:", ".HDF:", ".NXS:"}) {
    const auto p = spec.rfind(ext);
    if (p != std::string::npos) {
      const auto colon = p + std::string(ext).size() - 1;
      return {spec.substr(0, colon), spec.substr(colon + 1)};
    }
  }
  return {spec, ""};
}

bool is_hdf5(const std::string& spec) { return is_h5_ext(lower_ext(split_dataset_spec(spec).first)); }

FileFormat format_of(const std::string& spec, bool for_writing) {
  const auto [path, ds] = split_dataset_spec(spec);
  const std::string e = lower_ext(path);
  if (is_h5_ext(e)) return FileFormat::hdf5;
  if (e == ".tif" || e == ".tiff") return FileFormat::tiff;
  if (e == ".json") return FileFormat::raw;
  if (fs::is_directory(path) || (!path.empty() && path.back() == '/') || (for_writing && e.empty()))
    return FileFormat::tiff_folder;
  throw UsageError(path + ": unknown volume format '" + e +
                   "' (use .tif/.tiff, a folder of TIFF slices, .json raw sidecar, or .h5[:/dataset])");
}

static AnyVolume read_volume_unchecked(const std::string& spec, const ReadOptions& opt);

namespace {
// The dataset a spec names, or the default one: /volume, else /labels, else
// the file's only 3-D dataset (files written by other tools name theirs
// /data, /exchange/data, /segmentation, ...: one volume leaves no doubt).
std::string volume_dataset(const H5Reader& r, const std::string& path, const std::string& ds) {
  if (!ds.empty()) return ds;
  if (r.has("/volume")) return "/volume";
  if (r.has("/labels")) return "/labels";
  std::vector<std::string> volumes;
  for (const auto& d : r.datasets()) {
    if (r.rank(d) == 3) volumes.push_back(d);  // table columns are rank 1
  }
  if (volumes.size() == 1) return volumes.front();
  std::string listed;
  for (const auto& v : volumes) listed += (listed.empty() ? "" : ", ") + v;
  throw InputError(path + ": no /volume or /labels dataset" +
                   (volumes.empty() ? std::string(" and no 3-D dataset") : " and several 3-D ones (" + listed + ")") +
                   "; name one as " + path + ":/DATASET");
}
}  // namespace

SliceRange slices_within(SliceRange range, int64_t depth, const std::string& where) {
  if (range.nz < 0 && range.z0 >= 0) range.nz = depth - range.z0;
  if (range.z0 < 0 || range.nz < 1 || range.z0 + range.nz > depth)
    throw InputError(where + ": slices [" + std::to_string(range.z0) + ", " +
                     (range.nz < 0 ? std::string("end") : std::to_string(range.z0 + range.nz)) + ") are not within its " +
                     std::to_string(depth) + " slices");
  return range;
}

VolumeInfo read_volume_info(const std::string& spec, const ReadOptions& opt) {
  const auto [path, ds] = split_dataset_spec(spec);
  if (!fs::exists(path)) throw InputError(path + ": no such file or folder");
  int64_t depth = 0;
  switch (format_of(spec, false)) {
    case FileFormat::tiff: depth = tiff_page_count(path); break;
    case FileFormat::tiff_folder: depth = static_cast<int64_t>(tiff_slices_in(path).size()); break;
    case FileFormat::raw: depth = raw_shape(path).nz; break;
    case FileFormat::hdf5: {
      H5Reader r(path);
      depth = r.shape(volume_dataset(r, path, ds)).nz;
      break;
    }
  }
  // Type, slice size and geometry from the first slice (its origin is the file's).
  ReadOptions one = opt;
  one.slices = {0, 1};
  one.progress = false;
  one.nonfinite = NonFinite::allow;
  one.reuse = nullptr;
  const AnyVolume first = read_volume(spec, one);
  const Shape s = shape_of(first);
  return VolumeInfo{Shape{depth, s.ny, s.nx}, dtype_of(first), geometry_of(first)};
}

std::pair<int64_t, int64_t> count_nonfinite(const Volume<float>& v) {
  int64_t n = 0, first = -1;
  const float* p = v.data();
  const int64_t size = v.size();
#pragma omp parallel for schedule(static) reduction(+ : n)
  for (int64_t i = 0; i < size; ++i) n += !std::isfinite(p[i]);
  if (n > 0)
    for (int64_t i = 0; i < size; ++i)
      if (!std::isfinite(p[i])) { first = i; break; }
  return {n, first};
}

AnyVolume read_volume(const std::string& spec, const ReadOptions& opt) {
  try {
    return read_volume_unchecked(spec, opt);
  } catch (const ResourceError& e) {
    // Allocation and size checks deep in the readers do not know the file: name it here.
    const std::string what = e.what();
    if (what.rfind(split_dataset_spec(spec).first, 0) == 0) throw;
    throw ResourceError(spec + ": " + what);
  }
}

static AnyVolume read_volume_unchecked(const std::string& spec, const ReadOptions& opt) {
  const auto [path, ds] = split_dataset_spec(spec);
  if (!fs::exists(path)) throw InputError(path + ": no such file or folder");
  AnyVolume v;
  switch (format_of(spec, false)) {
    case FileFormat::tiff: v = read_tiff(path, opt.progress, opt.slices); break;
    case FileFormat::tiff_folder: v = read_tiff_folder(path, opt.progress, opt.slices); break;
    case FileFormat::raw: v = read_raw(path, opt.progress, opt.slices); break;
    case FileFormat::hdf5: {
      H5Reader r(path);
      const std::string name = volume_dataset(r, path, ds);
      if (opt.slices.whole()) {
        v = r.read_volume(name, opt.progress, opt.reuse);
      } else {
        const SliceRange s = slices_within(opt.slices, r.shape(name).nz, spec);
        v = r.read_slab(name, s.z0, s.nz, opt.reuse);
      }
      break;
    }
  }
  if (opt.voxel_um > 0) {
    Geometry g = geometry_of(v);
    g.voxel_size_m = {opt.voxel_um * 1e-6, opt.voxel_um * 1e-6, opt.voxel_um * 1e-6};
    set_geometry(v, g);
  }
  if (opt.nonfinite == NonFinite::error) {
    if (auto* f = std::get_if<Volume<float>>(&v)) {
      const auto [n, first] = count_nonfinite(*f);
      if (n > 0) {
        const auto c = f->shape().coords(first);
        throw InputError(spec + ": " + std::to_string(n) + " NaN/Inf voxel(s), first at (z,y,x)=(" +
                         std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]) +
                         "); replace them before processing (policy: non-finite grey values are rejected)");
      }
    }
  }
  return v;
}

Volume<uint32_t> read_label_volume(const std::string& spec, const ReadOptions& opt) {
  AnyVolume v = read_volume(spec, opt);
  if (auto* p = std::get_if<Volume<uint32_t>>(&v)) return std::move(*p);
  if (auto* f = std::get_if<Volume<float>>(&v)) {
    // Labels stored as floats are exact integers up to 2^24.
    const float* d = f->data();
    for (int64_t i = 0; i < f->size(); ++i)
      if (!(d[i] >= 0.f && d[i] <= 16777216.f && d[i] == std::floor(d[i]))) {
        const auto c = f->shape().coords(i);
        throw InputError(spec + ": holds float32 value " + std::to_string(d[i]) + " at (z,y,x)=(" +
                         std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]) +
                         "), not a label (an integer 0..16777216): a grey scan where labels were expected?");
      }
  }
  return std::visit(
      [&](const auto& src) {
        Volume<uint32_t> out(src.shape(), src.geometry());
        const auto* d = src.data();
        uint32_t* o = out.data();
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < src.size(); ++i) o[i] = static_cast<uint32_t>(d[i]);
        return out;
      },
      v);
}

template <class T>
Volume<T> read_volume_as(const std::string& spec, const ReadOptions& opt) {
  AnyVolume v = read_volume(spec, opt);
  if (auto* p = std::get_if<Volume<T>>(&v)) return std::move(*p);
  throw InputError(spec + ": holds " + std::string(dtype_name(dtype_of(v))) + ", expected " +
                   dtype_name(dtype_of<T>()));
}

template <class T>
void write_volume(const Volume<T>& v, const std::string& spec, const WriteOptions& opt) {
  const auto [path, ds] = split_dataset_spec(spec);
  switch (format_of(spec, true)) {
    case FileFormat::tiff: write_tiff(v, path, opt.progress); return;
    case FileFormat::tiff_folder: write_tiff_folder(v, path, opt.progress); return;
    case FileFormat::raw: write_raw(v, path, opt.progress); return;
    case FileFormat::hdf5: {
      H5Writer w(path);
      w.write_volume(!ds.empty() ? ds : dtype_of<T>() == DType::u32 ? "/labels" : "/volume", v, opt.compression);
      w.commit();
      return;
    }
  }
}

void write_volume(const AnyVolume& v, const std::string& spec, const WriteOptions& opt) {
  std::visit([&](const auto& vol) { write_volume(vol, spec, opt); }, v);
}

template Volume<uint8_t> read_volume_as(const std::string&, const ReadOptions&);
template Volume<uint16_t> read_volume_as(const std::string&, const ReadOptions&);
template Volume<uint32_t> read_volume_as(const std::string&, const ReadOptions&);
template Volume<float> read_volume_as(const std::string&, const ReadOptions&);
template void write_volume(const Volume<uint8_t>&, const std::string&, const WriteOptions&);
template void write_volume(const Volume<uint16_t>&, const std::string&, const WriteOptions&);
template void write_volume(const Volume<uint32_t>&, const std::string&, const WriteOptions&);
template void write_volume(const Volume<float>&, const std::string&, const WriteOptions&);

}  // namespace tg

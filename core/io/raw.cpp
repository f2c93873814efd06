#include "core/io/raw.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/io/volume_io.hpp"
#include "core/progress.hpp"

namespace tg {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

constexpr int64_t kChunk = int64_t{64} << 20;  // bytes per read/write call (progress granularity)

std::array<double, 3> three(const json& j, const std::string& key, double scale, const std::string& path) {
  if (j.is_number()) {
    const double v = j.get<double>() * scale;
    return {v, v, v};
  }
  if (j.is_array() && j.size() == 3 && std::all_of(j.begin(), j.end(), [](const json& e) { return e.is_number(); }))
    return {j[0].get<double>() * scale, j[1].get<double>() * scale, j[2].get<double>() * scale};
  throw InputError(path + ": '" + key + "' must be a number or an array of 3 numbers (z, y, x)");
}

template <class T>
void byteswap_all(T* p, int64_t n) {
  if constexpr (sizeof(T) > 1) {
    for (int64_t i = 0; i < n; ++i) {
      auto* b = reinterpret_cast<unsigned char*>(p + i);
      std::reverse(b, b + sizeof(T));
    }
  }
}

}  // namespace

namespace {

// What the sidecar says, checked against the raw file's size.
struct Sidecar {
  Shape shape;
  DType dtype = DType::u16;
  bool big_endian = false;
  Geometry geometry;
  int64_t header = 0;
  fs::path raw;
};

Sidecar read_sidecar_checked(const std::string& path) {
  std::ifstream jf(path);
  if (!jf) throw InputError(path + ": cannot open sidecar");
  json h;
  try {
    h = json::parse(jf);
  } catch (const json::exception& e) {
    throw InputError(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (!h.is_object()) throw InputError(path + ": sidecar must be a JSON object");
  const json& sh = h.value("shape_zyx", json());
  if (!sh.is_array() || sh.size() != 3 ||
      !std::all_of(sh.begin(), sh.end(), [](const json& e) { return e.is_number_integer(); }))
    throw InputError(path + ": 'shape_zyx' must be an array of 3 integers");
  Sidecar c;
  c.shape = Shape{sh[0].get<int64_t>(), sh[1].get<int64_t>(), sh[2].get<int64_t>()};
  if (c.shape.nz <= 0 || c.shape.ny <= 0 || c.shape.nx <= 0)
    throw InputError(path + ": 'shape_zyx' " + c.shape.str() + " must be positive");
  try {
    if (h.contains("dtype")) c.dtype = parse_dtype(h["dtype"].get<std::string>());
  } catch (const std::exception& e) {
    throw InputError(path + ": 'dtype': " + e.what());
  }
  const std::string order = h.value("byte_order", std::string("little"));
  if (order != "little" && order != "big") throw InputError(path + ": 'byte_order' must be \"little\" or \"big\"");
  c.big_endian = order == "big";
  Geometry& g = c.geometry;
  if (h.contains("voxel_size_m")) g.voxel_size_m = three(h["voxel_size_m"], "voxel_size_m", 1.0, path);
  else if (h.contains("voxel_size_um")) g.voxel_size_m = three(h["voxel_size_um"], "voxel_size_um", 1e-6, path);
  else if (h.contains("voxel_mm")) g.voxel_size_m = three(h["voxel_mm"], "voxel_mm", 1e-3, path);
  for (double v : g.voxel_size_m)
    if (!(std::isfinite(v) && v >= 0)) throw InputError(path + ": voxel size must be a positive number");
  if (h.contains("origin_m")) g.origin_m = three(h["origin_m"], "origin_m", 1.0, path);
  c.header = h.value("header_bytes", int64_t{0});
  if (c.header < 0) throw InputError(path + ": 'header_bytes' must be >= 0");
  std::string raw_name = fs::path(path).stem().string() + ".raw";
  if (h.contains("files") && h["files"].is_object() && h["files"].contains("volume_raw"))
    raw_name = h["files"]["volume_raw"].get<std::string>();
  c.raw = fs::path(path).parent_path() / raw_name;
  if (!fs::is_regular_file(c.raw)) throw InputError(c.raw.string() + ": raw data file named by " + path + " not found");
  const int64_t nbytes = c.shape.voxels() * dtype_bytes(c.dtype);  // voxels() throws on overflow
  const int64_t fsize = static_cast<int64_t>(fs::file_size(c.raw));
  if (fsize != c.header + nbytes)
    throw InputError(c.raw.string() + ": file has " + std::to_string(fsize) + " bytes, sidecar " + path + " implies " +
                     std::to_string(c.header + nbytes) + " (" + c.shape.str() + " " + dtype_name(c.dtype) + ")");
  return c;
}

// A field of the wrong JSON type ("byte_order": 2) is bad input, not an internal error.
Sidecar read_sidecar(const std::string& path) {
  try {
    return read_sidecar_checked(path);
  } catch (const json::exception& e) {
    throw InputError(path + ": invalid sidecar field (" + std::string(e.what()) + ")");
  }
}

}  // namespace

Shape raw_shape(const std::string& json_path) { return read_sidecar(json_path).shape; }

AnyVolume read_raw(const std::string& path, bool progress, SliceRange slices) {
  const Sidecar c = read_sidecar(path);
  const SliceRange r = slices_within(slices, c.shape.nz, path);
  const Shape shape{r.nz, c.shape.ny, c.shape.nx};
  Geometry g = c.geometry;
  g.origin_m[0] += double(r.z0) * g.voxel_size_m[0];
  const int64_t nbytes = shape.voxels() * dtype_bytes(c.dtype);
  AnyVolume out = make_volume(c.dtype, shape, g);
  std::visit(
      [&](auto& v) {
        std::ifstream f(c.raw, std::ios::binary);
        f.seekg(c.header + r.z0 * c.shape.slice_voxels() * dtype_bytes(c.dtype));
        auto* p = reinterpret_cast<char*>(v.data());
        Progress bar("reading " + c.raw.filename().string(), static_cast<double>(nbytes));
        for (int64_t off = 0; off < nbytes; off += kChunk) {
          const int64_t n = std::min(kChunk, nbytes - off);
          if (!f.read(p + off, n)) throw InputError(c.raw.string() + ": read failed at byte " + std::to_string(off));
          if (progress) bar.update(static_cast<double>(off + n));
        }
        if (c.big_endian == (std::endian::native == std::endian::little)) byteswap_all(v.data(), v.size());
      },
      out);
  return out;
}

template <class T>
void write_raw(const Volume<T>& v, const std::string& path, bool progress) {
  {
      {
        const fs::path raw = fs::path(path).parent_path() / (fs::path(path).stem().string() + ".raw");
        AtomicPath out_raw(raw), out_json(path);
        {
          std::ofstream f(out_raw.temp(), std::ios::binary);
          static_assert(std::endian::native == std::endian::little, "writer assumes a little-endian host");
          const auto* p = reinterpret_cast<const char*>(v.data());
          Progress bar("writing " + raw.filename().string(), static_cast<double>(v.bytes()));
          for (int64_t off = 0; off < v.bytes(); off += kChunk) {
            const int64_t n = std::min(kChunk, v.bytes() - off);
            f.write(p + off, n);
            if (progress) bar.update(static_cast<double>(off + n));
          }
          if (!f) throw InputError(raw.string() + ": cannot write");
        }
        json h;
        const auto& s = v.shape();
        h["format"] = "tomograin-raw-1";
        h["shape_zyx"] = {s.nz, s.ny, s.nx};
        h["dtype"] = dtype_name(dtype_of<typename std::decay_t<decltype(v)>::value_type>());
        h["byte_order"] = "little";
        const auto& g = v.geometry();
        if (g.has_voxel_size()) h["voxel_size_m"] = g.voxel_size_m;
        h["origin_m"] = g.origin_m;
        h["files"]["volume_raw"] = raw.filename().string();
        {
          std::ofstream f(out_json.temp());
          f << h.dump(2) << "\n";
          if (!f) throw InputError(path + ": cannot write");
        }
        out_raw.commit();
        out_json.commit();
      }
  }
}

void write_raw(const AnyVolume& v, const std::string& path, bool progress) {
  std::visit([&](const auto& vol) { write_raw(vol, path, progress); }, v);
}
template void write_raw(const Volume<uint8_t>&, const std::string&, bool);
template void write_raw(const Volume<uint16_t>&, const std::string&, bool);
template void write_raw(const Volume<uint32_t>&, const std::string&, bool);
template void write_raw(const Volume<float>&, const std::string&, bool);

}  // namespace tg

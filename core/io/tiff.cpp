#include "core/io/tiff.hpp"

#include <tiffio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <type_traits>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/io/volume_io.hpp"
#include "core/progress.hpp"

namespace tg {
namespace fs = std::filesystem;

namespace {

// libtiff reports through global handlers; keep the last error per thread so
// our exception can say what libtiff saw, and print nothing ourselves.
thread_local std::string g_tiff_error;
void on_tiff_error(const char* module, const char* fmt, va_list ap) {
  char buf[512];
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  g_tiff_error = (module ? std::string(module) + ": " : std::string()) + buf;
}
void on_tiff_warning(const char*, const char*, va_list) {}
struct HandlersInstalled {
  HandlersInstalled() {
    TIFFSetErrorHandler(on_tiff_error);
    TIFFSetWarningHandler(on_tiff_warning);
  }
};
void install_handlers() { static HandlersInstalled once; }

struct TiffCloser {
  void operator()(TIFF* t) const { if (t) TIFFClose(t); }
};
using TiffPtr = std::unique_ptr<TIFF, TiffCloser>;

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  std::string msg = path + ": " + what;
  if (!g_tiff_error.empty()) msg += " (" + g_tiff_error + ")";
  g_tiff_error.clear();
  throw InputError(msg);
}

struct PageInfo {
  uint32_t width = 0, height = 0;
  DType dtype = DType::u8;  // the volume's element type
  // Signed or 64-bit integer pages (label volumes from other tools: Python's
  // labelling functions give int32/int64) are read into uint32 with every
  // value checked to be a label, 0..2^32-1: src_bits is their width.
  int src_bits = 0;
  bool src_signed = false;
};

PageInfo page_info(TIFF* t, const std::string& path, int page) {
  PageInfo p;
  uint16_t bits = 0, fmt = SAMPLEFORMAT_UINT, spp = 1, planar = PLANARCONFIG_CONTIG;
  if (!TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &p.width) || !TIFFGetField(t, TIFFTAG_IMAGELENGTH, &p.height))
    fail(path, "page " + std::to_string(page) + " has no image size");
  TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &fmt);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(t, TIFFTAG_PLANARCONFIG, &planar);
  if (spp != 1)
    fail(path, "page " + std::to_string(page) + " has " + std::to_string(spp) +
                   " samples per pixel; only single-channel (grey) volumes are supported");
  if (fmt == SAMPLEFORMAT_IEEEFP && bits == 32) p.dtype = DType::f32;
  else if ((fmt == SAMPLEFORMAT_UINT || fmt == SAMPLEFORMAT_VOID) && bits == 8) p.dtype = DType::u8;
  else if ((fmt == SAMPLEFORMAT_UINT || fmt == SAMPLEFORMAT_VOID) && bits == 16) p.dtype = DType::u16;
  else if ((fmt == SAMPLEFORMAT_UINT || fmt == SAMPLEFORMAT_VOID) && bits == 32) p.dtype = DType::u32;
  else if ((fmt == SAMPLEFORMAT_INT && (bits == 8 || bits == 16 || bits == 32 || bits == 64)) ||
           ((fmt == SAMPLEFORMAT_UINT || fmt == SAMPLEFORMAT_VOID) && bits == 64)) {
    p.dtype = DType::u32;
    p.src_bits = bits;
    p.src_signed = fmt == SAMPLEFORMAT_INT;
  } else
    fail(path, "page " + std::to_string(page) + ": " + std::to_string(bits) + "-bit sample format " +
                   std::to_string(fmt) +
                   " is not supported (8/16/32-bit unsigned or 32-bit float; signed or 64-bit integers as labels)");
  if (p.width == 0 || p.height == 0) fail(path, "page " + std::to_string(page) + " is empty (0 pixels)");
  return p;
}

// Decodes the current page into dst (height*width samples of bps bytes).
void decode_page(TIFF* t, const std::string& path, int page, const PageInfo& p, int bps, unsigned char* dst) {
  const int64_t row_bytes = static_cast<int64_t>(p.width) * bps;
  const int64_t page_bytes = row_bytes * p.height;
  if (TIFFIsTiled(t)) {
    uint32_t tw = 0, th = 0;
    TIFFGetField(t, TIFFTAG_TILEWIDTH, &tw);
    TIFFGetField(t, TIFFTAG_TILELENGTH, &th);
    if (tw == 0 || th == 0) fail(path, "page " + std::to_string(page) + " has a zero tile size");
    const tmsize_t tile_bytes = TIFFTileSize(t);
    if (tile_bytes != static_cast<tmsize_t>(tw) * th * bps) fail(path, "unexpected tile size");
    // A tile larger than its page (and than any tile a writer would pick)
    // comes from a corrupt header: refuse it before allocating it (found by
    // fuzzing: a 374-byte file asked for a 7.3 GB tile buffer).
    constexpr int64_t kMaxTileBytes = int64_t(64) << 20;
    if (static_cast<int64_t>(tile_bytes) > std::max(page_bytes, kMaxTileBytes))
      fail(path, "page " + std::to_string(page) + " declares " + std::to_string(tw) + " x " + std::to_string(th) +
                     " tiles, larger than the " + std::to_string(p.width) + " x " + std::to_string(p.height) +
                     " page: corrupt header");
    std::vector<unsigned char> tile(static_cast<size_t>(tile_bytes));
    for (uint32_t y0 = 0; y0 < p.height; y0 += th)
      for (uint32_t x0 = 0; x0 < p.width; x0 += tw) {
        if (TIFFReadTile(t, tile.data(), x0, y0, 0, 0) < 0)
          fail(path, "page " + std::to_string(page) + " is truncated or corrupt");
        const uint32_t h = std::min(th, p.height - y0), w = std::min(tw, p.width - x0);
        for (uint32_t y = 0; y < h; ++y)
          std::memcpy(dst + (y0 + y) * row_bytes + static_cast<int64_t>(x0) * bps,
                      tile.data() + static_cast<size_t>(y) * tw * bps, static_cast<size_t>(w) * bps);
      }
    return;
  }
  const tstrip_t nstrips = TIFFNumberOfStrips(t);
  int64_t off = 0;
  for (tstrip_t s = 0; s < nstrips && off < page_bytes; ++s) {
    const tmsize_t want = static_cast<tmsize_t>(std::min<int64_t>(TIFFStripSize(t), page_bytes - off));
    const tmsize_t got = TIFFReadEncodedStrip(t, s, dst + off, want);
    if (got < 0) fail(path, "page " + std::to_string(page) + " is truncated or corrupt");
    off += got;
  }
  if (off != page_bytes)
    fail(path, "page " + std::to_string(page) + " holds " + std::to_string(off) + " bytes of pixel data, expected " +
                   std::to_string(page_bytes));
}

// One sample of a signed or 64-bit integer page, as a label.
template <class S>
void samples_to_labels(const unsigned char* src, uint32_t* dst, int64_t n, const std::string& path, int page,
                       uint32_t width) {
  for (int64_t i = 0; i < n; ++i) {
    S v;
    std::memcpy(&v, src + i * int64_t(sizeof(S)), sizeof(S));
    bool negative = false;
    if constexpr (std::is_signed_v<S>) negative = v < 0;
    if (negative || static_cast<uint64_t>(v) > 0xffffffffull)
      fail(path, "page " + std::to_string(page) + ": value " + std::to_string(v) + " at (y,x)=(" +
                     std::to_string(i / width) + "," + std::to_string(i % width) +
                     ") is not a label (0..4294967295): a signed or 64-bit integer TIFF is read as labels only");
    dst[i] = static_cast<uint32_t>(v);
  }
}

// Decodes the current page into dst (height*width elements of p.dtype).
void read_page(TIFF* t, const std::string& path, int page, const PageInfo& p, unsigned char* dst) {
  if (p.src_bits == 0) return decode_page(t, path, page, p, dtype_bytes(p.dtype), dst);
  const int64_t n = int64_t(p.width) * p.height;
  std::vector<unsigned char> raw(static_cast<size_t>(n * (p.src_bits / 8)));
  decode_page(t, path, page, p, p.src_bits / 8, raw.data());
  auto* out = reinterpret_cast<uint32_t*>(dst);
  switch (p.src_bits * (p.src_signed ? -1 : 1)) {
    case -8: return samples_to_labels<int8_t>(raw.data(), out, n, path, page, p.width);
    case -16: return samples_to_labels<int16_t>(raw.data(), out, n, path, page, p.width);
    case -32: return samples_to_labels<int32_t>(raw.data(), out, n, path, page, p.width);
    case -64: return samples_to_labels<int64_t>(raw.data(), out, n, path, page, p.width);
    default: return samples_to_labels<uint64_t>(raw.data(), out, n, path, page, p.width);
  }
}

double unit_to_m(std::string u) {
  for (auto& c : u) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (u == "micron" || u == "um" || u == "\xb5m" || u == "\xc2\xb5m" || u == "microns" || u == "micrometer") return 1e-6;
  if (u == "mm" || u == "millimeter" || u == "millimetre") return 1e-3;
  if (u == "nm" || u == "nanometer") return 1e-9;
  if (u == "cm" || u == "centimeter") return 1e-2;
  if (u == "m" || u == "meter" || u == "metre") return 1.0;
  return 0;
}

// Voxel size from ImageJ description or centimetre resolution tags (first page).
Geometry read_geometry(TIFF* t) {
  Geometry g;
  float xres = 0, yres = 0;
  uint16_t resunit = RESUNIT_INCH;
  const bool has_x = TIFFGetField(t, TIFFTAG_XRESOLUTION, &xres) && xres > 0;
  const bool has_y = TIFFGetField(t, TIFFTAG_YRESOLUTION, &yres) && yres > 0;
  TIFFGetFieldDefaulted(t, TIFFTAG_RESOLUTIONUNIT, &resunit);
  char* desc = nullptr;
  std::string d;
  if (TIFFGetField(t, TIFFTAG_IMAGEDESCRIPTION, &desc) && desc) d = desc;
  if (d.rfind("ImageJ=", 0) == 0) {
    auto value = [&](const std::string& key) -> std::string {
      const auto p = d.find("\n" + key + "=");
      if (p == std::string::npos) return "";
      const auto b = p + key.size() + 2, e = d.find('\n', b);
      return d.substr(b, e == std::string::npos ? std::string::npos : e - b);
    };
    const double scale = unit_to_m(value("unit"));
    if (scale > 0 && has_x && has_y) {
      g.voxel_size_m[2] = scale / xres;
      g.voxel_size_m[1] = scale / yres;
      const std::string sp = value("spacing");
      g.voxel_size_m[0] = sp.empty() ? g.voxel_size_m[2] : scale * std::atof(sp.c_str());
      if (!(g.voxel_size_m[0] > 0)) g.voxel_size_m = {0, 0, 0};
      return g;
    }
  }
  if (resunit == RESUNIT_CENTIMETER && has_x && has_y) {
    g.voxel_size_m[2] = 0.01 / xres;
    g.voxel_size_m[1] = 0.01 / yres;
    g.voxel_size_m[0] = g.voxel_size_m[2];  // TIFF has no z spacing: assume isotropic
  }
  return g;
}

// The origin of slices starting at z0: the file's, moved down z0 slices.
Geometry slab_geometry(Geometry g, int64_t z0) {
  g.origin_m[0] += double(z0) * g.voxel_size_m[0];
  return g;
}

// Pages [r.z0, r.z0 + r.nz) (a range within the file); t at page 0.
template <class T>
Volume<T> read_pages(TIFF* t, const std::string& path, SliceRange r, const PageInfo& first, bool progress) {
  Volume<T> v(Shape{r.nz, first.height, first.width}, slab_geometry(read_geometry(t), r.z0));
  if (r.z0 > 0 && !TIFFSetDirectory(t, static_cast<tdir_t>(r.z0)))
    fail(path, "page " + std::to_string(r.z0) + " cannot be read");
  Progress bar("reading " + fs::path(path).filename().string(), double(r.nz));
  for (int64_t q = 0; q < r.nz; ++q) {
    const int64_t k = r.z0 + q;
    if (q > 0 && !TIFFReadDirectory(t)) fail(path, "page " + std::to_string(k) + " cannot be read");
    const PageInfo p = page_info(t, path, int(k));
    if (p.width != first.width || p.height != first.height || p.dtype != first.dtype)
      fail(path, "page " + std::to_string(k) + " is " + std::to_string(p.width) + "x" + std::to_string(p.height) +
                     " " + dtype_name(p.dtype) + ", page 0 is " + std::to_string(first.width) + "x" +
                     std::to_string(first.height) + " " + dtype_name(first.dtype));
    read_page(t, path, int(k), p, reinterpret_cast<unsigned char*>(v.data() + q * v.shape().slice_voxels()));
    if (progress) bar.update(double(q + 1));
  }
  return v;
}

TiffPtr open_read(const std::string& path) {
  install_handlers();
  if (!fs::is_regular_file(path)) throw InputError(path + ": no such file");
  TiffPtr t(TIFFOpen(path.c_str(), "rm"));  // m: no memory-mapping, so truncation shows as a read error
  if (!t) fail(path, "not a readable TIFF file");
  return t;
}

template <class T>
void set_page_tags(TIFF* t, const Volume<T>& v, int64_t k, const std::string& desc) {
  const auto& s = v.shape();
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(s.nx));
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(s.ny));
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, static_cast<uint16_t>(8 * sizeof(T)));
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, static_cast<uint16_t>(1));
  TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, std::is_floating_point_v<T> ? SAMPLEFORMAT_IEEEFP : SAMPLEFORMAT_UINT);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_NONE);
  const int64_t row_bytes = s.nx * static_cast<int64_t>(sizeof(T));
  const uint32_t rows_per_strip = static_cast<uint32_t>(std::max<int64_t>(1, (256 * 1024) / std::max<int64_t>(1, row_bytes)));
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, std::min<uint32_t>(rows_per_strip, static_cast<uint32_t>(s.ny)));
  const auto& g = v.geometry();
  if (g.has_voxel_size()) {
    TIFFSetField(t, TIFFTAG_XRESOLUTION, static_cast<float>(1e-6 / g.voxel_size_m[2]));
    TIFFSetField(t, TIFFTAG_YRESOLUTION, static_cast<float>(1e-6 / g.voxel_size_m[1]));
    TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_NONE);
  }
  if (k == 0 && !desc.empty()) TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, desc.c_str());
}

std::string imagej_description(const Shape& s, const Geometry& g, bool multipage) {
  std::string d = "ImageJ=1.53t\n";
  if (multipage) d += "images=" + std::to_string(s.nz) + "\nslices=" + std::to_string(s.nz) + "\n";
  if (g.has_voxel_size()) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", g.voxel_size_m[0] * 1e6);
    d += std::string("unit=micron\nspacing=") + buf + "\n";
  }
  d += "loop=false\n";
  return d;
}

template <class T>
void write_page(TIFF* t, const Volume<T>& v, int64_t k, const std::string& path) {
  const auto& s = v.shape();
  const unsigned char* src = reinterpret_cast<const unsigned char*>(v.data() + k * s.slice_voxels());
  const int64_t row_bytes = s.nx * static_cast<int64_t>(sizeof(T));
  uint32_t rps = 0;
  TIFFGetField(t, TIFFTAG_ROWSPERSTRIP, &rps);
  tstrip_t strip = 0;
  for (int64_t y = 0; y < s.ny; y += rps, ++strip) {
    const int64_t rows = std::min<int64_t>(rps, s.ny - y);
    if (TIFFWriteEncodedStrip(t, strip, const_cast<unsigned char*>(src + y * row_bytes), rows * row_bytes) < 0)
      fail(path, "cannot write page " + std::to_string(k));
  }
  if (!TIFFWriteDirectory(t)) fail(path, "cannot write page " + std::to_string(k));
}

void check_writable_shape(const Shape& s, const std::string& path) {
  if (s.empty()) throw UsageError(path + ": cannot write an empty volume " + s.str() + " as TIFF");
  if (s.nx > UINT32_MAX || s.ny > UINT32_MAX)
    throw UsageError(path + ": slice " + s.str() + " too large for TIFF");
}

}  // namespace

std::vector<std::string> tiff_slices_in(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::string ext = e.path().extension().string();
    for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const std::string fn = e.path().filename().string();
    if ((ext == ".tif" || ext == ".tiff") && fn[0] != '.') names.push_back(fn);
  }
  if (names.empty()) throw InputError(dir + ": folder holds no .tif/.tiff slices");
  std::sort(names.begin(), names.end(), natural_less);
  return names;
}

namespace {

// The slices of a multi-page TIFF. ImageJ saves a stack past 4 GB (and
// may save any stack) as ONE directory, "images=N" in its description and
// the N pages' pixels stored one after the other, uncompressed, from page
// 0's first strip: `contiguous` then, the pages read straight from the file
// (as ImageJ and tifffile read them).
struct TiffStack {
  int64_t pages = 0;
  bool contiguous = false;
  uint64_t offset = 0;     // contiguous: file offset of page 0's pixels
  int64_t page_bytes = 0;  // contiguous: bytes of one page
};

TiffStack stack_of(TIFF* t, const std::string& path) {
  g_tiff_error.clear();
  TiffStack st;
  st.pages = TIFFNumberOfDirectories(t);
  if (st.pages <= 0) fail(path, "TIFF holds no pages");
  // A cut file keeps its first pages readable; libtiff then reports a broken
  // link to the next page. Refuse it rather than return fewer slices.
  if (!g_tiff_error.empty())
    fail(path, "truncated or corrupt: the chain of pages breaks after page " + std::to_string(st.pages - 1));
  TIFFSetDirectory(t, 0);
  char* desc = nullptr;
  if (!(TIFFGetField(t, TIFFTAG_IMAGEDESCRIPTION, &desc) && desc && std::strncmp(desc, "ImageJ=", 7) == 0)) return st;
  const char* im = std::strstr(desc, "\nimages=");
  const int64_t images = im ? std::atoll(im + 8) : 0;
  if (images <= st.pages) return st;
  const auto truncated = [&](const std::string& why) {
    fail(path, "truncated: ImageJ metadata announces " + std::to_string(images) + " pages, file holds " +
                   std::to_string(st.pages) + why);
  };
  // One directory for many images: contiguous pixels, if everything says so.
  const PageInfo p = page_info(t, path, 0);
  uint16_t compression = COMPRESSION_NONE;
  TIFFGetFieldDefaulted(t, TIFFTAG_COMPRESSION, &compression);
  if (st.pages != 1 || TIFFIsTiled(t) || compression != COMPRESSION_NONE || p.src_bits != 0) truncated("");
  const tstrip_t nstrips = TIFFNumberOfStrips(t);
  uint64_t *offsets = nullptr, *counts = nullptr;
  if (nstrips == 0 || !TIFFGetField(t, TIFFTAG_STRIPOFFSETS, &offsets) || !TIFFGetField(t, TIFFTAG_STRIPBYTECOUNTS, &counts))
    truncated("");
  st.page_bytes = int64_t(p.width) * p.height * dtype_bytes(p.dtype);
  for (tstrip_t k = 0; k + 1 < nstrips; ++k)
    if (offsets[k + 1] != offsets[k] + counts[k]) truncated(" (page 0's strips are not contiguous)");
  st.offset = offsets[0];
  const uint64_t need = st.offset + uint64_t(images) * uint64_t(st.page_bytes);
  const uint64_t size = fs::file_size(path);
  if (size < need)
    truncated(" and " + std::to_string(size) + " bytes, " + std::to_string(need) + " needed for contiguous pages");
  st.pages = images;
  st.contiguous = true;
  return st;
}

// Pages [r.z0, r.z0 + r.nz) of an ImageJ contiguous stack, straight from the file.
template <class T>
Volume<T> read_contiguous(TIFF* t, const std::string& path, const TiffStack& st, SliceRange r, const PageInfo& first,
                          bool progress) {
  Volume<T> v(Shape{r.nz, first.height, first.width}, slab_geometry(read_geometry(t), r.z0));
  std::ifstream f(path, std::ios::binary);
  f.seekg(static_cast<std::streamoff>(st.offset + uint64_t(r.z0) * uint64_t(st.page_bytes)));
  Progress bar("reading " + fs::path(path).filename().string(), double(r.nz));
  for (int64_t q = 0; q < r.nz; ++q) {
    if (!f.read(reinterpret_cast<char*>(v.data() + q * v.shape().slice_voxels()), st.page_bytes))
      fail(path, "page " + std::to_string(r.z0 + q) + " cannot be read");
    if (progress) bar.update(double(q + 1));
  }
  if (TIFFIsByteSwapped(t) && sizeof(T) > 1)
    for (T& x : v) {
      auto* b = reinterpret_cast<unsigned char*>(&x);
      std::reverse(b, b + sizeof(T));
    }
  return v;
}

}  // namespace

AnyVolume read_tiff(const std::string& path, bool progress, SliceRange slices) {
  TiffPtr t = open_read(path);
  const TiffStack st = stack_of(t.get(), path);
  const SliceRange r = slices_within(slices, st.pages, path);
  const PageInfo first = page_info(t.get(), path, 0);
  const auto read = [&](auto tag) -> AnyVolume {
    using T = decltype(tag);
    if (st.contiguous) return read_contiguous<T>(t.get(), path, st, r, first, progress);
    return read_pages<T>(t.get(), path, r, first, progress);
  };
  switch (first.dtype) {
    case DType::u8: return read(uint8_t{});
    case DType::u16: return read(uint16_t{});
    case DType::u32: return read(uint32_t{});
    case DType::f32: return read(float{});
  }
  fail(path, "unsupported sample type");
}

int64_t tiff_page_count(const std::string& path) {
  TiffPtr t = open_read(path);
  return stack_of(t.get(), path).pages;
}

AnyVolume read_tiff_folder(const std::string& dir, bool progress, SliceRange slices) {
  const auto names = tiff_slices_in(dir);
  const SliceRange r = slices_within(slices, static_cast<int64_t>(names.size()), dir);
  // Sizes, type and voxel size from the first slice of the folder, the
  // origin moved to the first slice read.
  const std::string first_path = (fs::path(dir) / names[0]).string();
  TiffPtr t0 = open_read(first_path);
  const PageInfo first = page_info(t0.get(), first_path, 0);
  const Geometry g = slab_geometry(read_geometry(t0.get()), r.z0);
  t0.reset();
  AnyVolume out = make_volume(first.dtype, Shape{r.nz, first.height, first.width}, g);
  Progress bar("reading " + fs::path(dir).filename().string(), static_cast<double>(r.nz));
  std::visit(
      [&](auto& v) {
        for (int64_t q = 0; q < r.nz; ++q) {
          const size_t k = static_cast<size_t>(r.z0 + q);
          const std::string p = (fs::path(dir) / names[k]).string();
          TiffPtr t = open_read(p);
          const PageInfo info = page_info(t.get(), p, 0);
          if (info.width != first.width || info.height != first.height || info.dtype != first.dtype)
            throw InputError(p + ": slice is " + std::to_string(info.width) + "x" + std::to_string(info.height) + " " +
                             dtype_name(info.dtype) + " but " + names[0] + " is " + std::to_string(first.width) + "x" +
                             std::to_string(first.height) + " " + dtype_name(first.dtype) + " (mixed slice sizes)");
          read_page(t.get(), p, 0, info, reinterpret_cast<unsigned char*>(v.data() + q * v.shape().slice_voxels()));
          if (progress) bar.update(static_cast<double>(q + 1));
        }
      },
      out);
  return out;
}

template <class T>
void write_tiff(const Volume<T>& v, const std::string& path, bool progress) {
  install_handlers();
  {
      {
        check_writable_shape(v.shape(), path);
        AtomicPath out(path);
        // Classic TIFF addresses 4 GiB; leave room for tags and offsets.
        const bool big = v.bytes() > (int64_t{4} << 30) - (int64_t{64} << 20);
        {
          TiffPtr t(TIFFOpen(out.temp().c_str(), big ? "w8" : "w"));
          if (!t) fail(path, "cannot create file");
          const std::string desc = imagej_description(v.shape(), v.geometry(), true);
          Progress bar("writing " + fs::path(path).filename().string(), static_cast<double>(v.shape().nz));
          for (int64_t k = 0; k < v.shape().nz; ++k) {
            set_page_tags(t.get(), v, k, desc);
            write_page(t.get(), v, k, path);
            if (progress) bar.update(static_cast<double>(k + 1));
          }
        }
        out.commit();
      }
  }
}

template <class T>
void write_tiff_folder(const Volume<T>& v, const std::string& dir, bool progress) {
  install_handlers();
  {
      {
        check_writable_shape(v.shape(), dir);
        fs::path target = fs::path(dir);
        if (target.filename().empty()) target = target.parent_path();  // trailing '/'
        AtomicPath out(target);
        fs::create_directory(out.temp());
        const int digits = std::max<int>(4, static_cast<int>(std::to_string(v.shape().nz - 1).size()));
        const std::string desc = imagej_description(v.shape(), v.geometry(), false);
        Progress bar("writing " + target.filename().string(), static_cast<double>(v.shape().nz));
        for (int64_t k = 0; k < v.shape().nz; ++k) {
          std::string num = std::to_string(k);
          const std::string name = "slice_" + std::string(num.size() < size_t(digits) ? digits - num.size() : 0, '0') + num + ".tif";
          const std::string p = (out.temp() / name).string();
          TiffPtr t(TIFFOpen(p.c_str(), "w"));
          if (!t) fail(p, "cannot create file");
          set_page_tags(t.get(), v, 0, desc);
          write_page(t.get(), v, k, p);
          if (progress) bar.update(static_cast<double>(k + 1));
        }
        out.commit();
      }
  }
}

void write_tiff(const AnyVolume& v, const std::string& path, bool progress) {
  std::visit([&](const auto& vol) { write_tiff(vol, path, progress); }, v);
}
void write_tiff_folder(const AnyVolume& v, const std::string& dir, bool progress) {
  std::visit([&](const auto& vol) { write_tiff_folder(vol, dir, progress); }, v);
}
#define TG_INSTANTIATE(T)                                                    \
  template void write_tiff(const Volume<T>&, const std::string&, bool);     \
  template void write_tiff_folder(const Volume<T>&, const std::string&, bool);
TG_INSTANTIATE(uint8_t)
TG_INSTANTIATE(uint16_t)
TG_INSTANTIATE(uint32_t)
TG_INSTANTIATE(float)
#undef TG_INSTANTIATE

}  // namespace tg

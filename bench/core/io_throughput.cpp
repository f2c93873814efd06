// Read and write throughput of a u16 volume (default 1 GiB: 512 x 1024 x 1024)
// in every format, beside a plain memcpy of the same bytes.
//
//   bench_io_throughput [--size-mib 1024] [--dir /tmp]
//
// Reads right after writes come from the page cache (what a user re-reading a
// file sees); the memcpy ratio says how far each path is from memory speed.
// The machine is shared: run when it is quiet and quote ratios.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>

#include "core/io/volume_io.hpp"
#include "core/memory.hpp"

namespace fs = std::filesystem;
using clk = std::chrono::steady_clock;

static double seconds(clk::time_point a) { return std::chrono::duration<double>(clk::now() - a).count(); }

int main(int argc, char** argv) {
  int64_t mib = 1024;
  std::string dir = fs::temp_directory_path().string();
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--size-mib") mib = std::stoll(argv[i + 1]);
    if (std::string(argv[i]) == "--dir") dir = argv[i + 1];
  }
  const int64_t nx = 1024, ny = 1024, nz = std::max<int64_t>(1, mib * 1024 * 1024 / (nx * ny * 2));
  tg::Volume<uint16_t> v(tg::Shape{nz, ny, nx}, tg::Geometry::isotropic_m(12.3e-6));
  std::mt19937 rng(1);
  for (auto& x : v) x = static_cast<uint16_t>(rng());
  const double gib = static_cast<double>(v.bytes()) / (1 << 30);

  tg::Volume<uint16_t> copy(v.shape());
  auto t0 = clk::now();
  std::memcpy(copy.data(), v.data(), static_cast<size_t>(v.bytes()));
  // Into fresh memory, the first copy pays the page faults a reader also pays
  // (readers fill a newly allocated volume); the second shows bare memory speed.
  const double t_memcpy = seconds(t0);
  t0 = clk::now();
  std::memcpy(copy.data(), v.data(), static_cast<size_t>(v.bytes()));
  const double t_warm = seconds(t0);
  std::printf("volume %s u16 = %.3f GiB; memcpy into new memory %.3f s (%.2f GiB/s), into touched memory %.3f s (%.2f GiB/s)\n",
              v.shape().str().c_str(), gib, t_memcpy, gib / t_memcpy, t_warm, gib / t_warm);
  std::printf("ratios below are against the first (same page-fault cost as a reader)\n");
  std::printf("%-22s %10s %10s %10s %10s %12s %12s\n", "format", "write s", "GiB/s", "read s", "GiB/s",
              "write/memcpy", "read/memcpy");
  const fs::path d = fs::path(dir) / ("tg_io_bench_" + std::to_string(::getpid()));
  fs::create_directories(d);
  for (const std::string name : {"v.tif", "slices/", "v.json", "v.h5", "vz.h5"}) {
    tg::WriteOptions wo;
    wo.progress = false;
    wo.compression = name == "vz.h5" ? 1 : 0;
    const std::string p = (d / name).string();
    t0 = clk::now();
    tg::write_volume(v, p, wo);
    const double tw = seconds(t0);
    tg::ReadOptions ro;
    ro.progress = false;
    t0 = clk::now();
    auto r = tg::read_volume_as<uint16_t>(p, ro);
    const double tr = seconds(t0);
    if (std::memcmp(r.data(), v.data(), static_cast<size_t>(v.bytes())) != 0) std::printf("MISMATCH in %s\n", name.c_str());
    const std::string label = name == "vz.h5" ? "hdf5 (deflate 1)" : name == "v.h5" ? "hdf5" : name == "v.json" ? "raw+json"
                              : name == "v.tif" ? "tiff multi-page" : "tiff slice folder";
    std::printf("%-22s %10.3f %10.2f %10.3f %10.2f %12.1f %12.1f\n", label.c_str(), tw, gib / tw, tr, gib / tr,
                tw / t_memcpy, tr / t_memcpy);
    fs::remove_all(p);
    if (name == "v.json") fs::remove(d / "v.raw");
  }
  fs::remove_all(d);
  std::printf("peak RSS %s\n", tg::human_bytes(static_cast<double>(tg::peak_rss_bytes())).c_str());
  return 0;
}

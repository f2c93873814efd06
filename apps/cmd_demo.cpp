// tomograin demo: the main job on an embedded default, end to end.
// Each stage prints what it ran and where the outputs are; later modules add
// their stage here (synthetic scan -> segment -> measure -> DEM -> compare).
#include <fmt/core.h>

#include <chrono>
#include <cmath>
#include <filesystem>

#include "apps/command.hpp"
#include "core/io/volume_io.hpp"
#include "core/stats.hpp"

namespace {
namespace fs = std::filesystem;

struct Opts {
  std::string out = "out/demo";
};

// Stage 1 (foundation): a small grey volume written as a TIFF slice folder,
// converted to HDF5 and raw+JSON and read back, as a scanner's output would be.
void stage_formats(const fs::path& dir) {
  const int64_t n = 64;
  tg::Volume<uint16_t> v(tg::Shape{n, n, n}, tg::Geometry::isotropic_m(12.3e-6));
  for (int64_t k = 0; k < n; ++k)
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i) {
        const double r = std::hypot(k + 0.5 - n / 2.0, j + 0.5 - n / 2.0, i + 0.5 - n / 2.0);
        v(k, j, i) = static_cast<uint16_t>(r < n / 3.0 ? 40000 : 10000);
      }
  tg::WriteOptions wo;
  wo.progress = false;
  tg::write_volume(v, (dir / "slices/").string(), wo);
  tg::ReadOptions ro;
  ro.progress = false;
  auto back = tg::read_volume((dir / "slices").string(), ro);
  tg::write_volume(back, (dir / "volume.h5").string(), wo);
  tg::write_volume(back, (dir / "volume.json").string(), wo);
  const auto st = tg::compute_stats(tg::read_volume((dir / "volume.json").string(), ro));
  fmt::print("[formats] 64^3 u16 volume: TIFF slices -> HDF5 -> raw+JSON; mean {:.1f}, {} of {} voxels at 40000\n",
             st.mean, st.hist.empty() ? 0 : st.hist.back(), st.voxels);
}

int run_demo(const Opts& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const fs::path dir(o.out);
  fs::create_directories(dir);
  stage_formats(dir);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  fmt::print("demo finished in {:.1f} s; outputs in {}\n", s, dir.string());
  return 0;
}

}  // namespace

static tg::app::Registrar reg{{"demo", 100, [](CLI::App& app, CLI::App*& sub) -> tg::app::Runner {
  sub = app.add_subcommand("demo",
                           "Run the whole chain on a small embedded default and print where the results are.\n\n"
                           "Example:\n  tomograin demo -o out/demo");
  auto o = std::make_shared<Opts>();
  sub->add_option("-o,--output", o->out, "Output folder")->capture_default_str();
  return [o] { return run_demo(*o); };
}}};

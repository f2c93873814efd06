// tomograin demo: the main job on an embedded default, end to end, as a study.
//   1. formats   a small volume through TIFF slices, HDF5 and raw+JSON
//   2. xct       synthetic `zeolite-stages` scans (stand-ins for the
//                experiment, labelled synthetic in the report)
//   3. study     `tomograin run` on the demo study (OUT/study.toml, written
//                here): analyse and track the stages, the DEM oedometer with
//                the breakage model on a small cell, voxelise its snapshots,
//                the same segmentation and measurement on both worlds, the
//                validation report and the study's summary
// Running it again re-uses the scans and does no study step twice (`run`
// skips what is up to date).
#include <fmt/core.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "apps/command.hpp"
#include "apps/config_args.hpp"
#include "apps/demo_toml.hpp"
#include "core/atomic_file.hpp"
#include "core/config.hpp"
#include "core/io/volume_io.hpp"
#include "core/stats.hpp"
#include "core/table.hpp"
#include "data_synth/scene.hpp"

namespace cmd_demo {
namespace fs = std::filesystem;
using clk = std::chrono::steady_clock;

// The demo's DEM: dem/examples/demo.toml (compiled in), the study's material,
// contact and breakage parameters (Table 1, fragments split again down to
// 0.2 mm) in a small Ø8 mm cell of ~126 grains; its one deviation, a smallest
// time step of 2e-8 s, and the measured candidates: bench/demo/RESULTS.md.
const std::string kDemoDem =
    "# tomograin demo oedometer (written by `tomograin demo`): dem/examples/demo.toml\n" + std::string(kDemoToml);

// The stages of data_synth's zeolite-stages preset (the study's strains).
const double kStrains[] = {0.0, 0.044, 0.0712, 0.1128, 0.1548};

std::string demo_study(int64_t xct_size) {
  std::string s = fmt::format(R"(# The demo study (written by `tomograin demo`; docs/studies.md explains every key).
[study]
name = "demo"
grain_diameter_um = 1360
)");
  for (int i = 0; i < 5; ++i)
    s += fmt::format("[[stage]]\nname = \"e{:02.0f}\"\nscan = \"scans_{}/xct_stage{}.h5\"\nstrain = {}\n",
                     100 * kStrains[i], xct_size, i, kStrains[i]);
  s += fmt::format(R"([track]
scans = true   # each particle's rotation from the stages' grey scans (track/lineage.csv rz_deg, ry_deg, rx_deg)
[dem]
config = "dem.toml"
[compare]
synthetic = true
title = "tomograin demo: synthetic XCT stages vs DEM with breakage"
notes = "What this demo ran: XCT = synthetic zeolite-stages scans of the DEM cell's 8 mm x 6 mm cylinder ({0}^3 voxels over 8.4 mm, seed 1; grains broken into halves, wedges and chips with the stage strain; NOT an experiment). DEM = ~126 grains pluviated into the 8 mm cell and compressed to 15.48 % strain with the study's breakage model (Table 1; fragments split again down to 0.2 mm). What the demo trades for time (bench/demo/RESULTS.md): a cell of ~126 grains instead of the study's 15 mm and 910; a smallest time step of 2e-8 s (3.6 % mass added to spheres below 0.1 mm); scans of the small cell at 30 um voxels (fine enough that the imaged DEM keeps >= 90 % of its particles one to one) instead of the whole specimen at 12.3 um. Both worlds go through the same segment() and measure (60 Feret orientations)."
)", xct_size);
  return s;
}

struct Opts {
  std::string out = "out/demo";
  int64_t xct_size = 280;  // 8.4 mm / 280 = 30 um voxels
};

double since(clk::time_point t0) { return std::chrono::duration<double>(clk::now() - t0).count(); }

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
  tg::ReadOptions ro;
  ro.progress = false;
  tg::write_volume(v, (dir / "slices/").string(), wo);
  auto back = tg::read_volume((dir / "slices").string(), ro);
  tg::write_volume(back, (dir / "volume.h5").string(), wo);
  tg::write_volume(back, (dir / "volume.json").string(), wo);
  const auto st = tg::compute_stats(tg::read_volume((dir / "volume.json").string(), ro));
  fmt::print("[1/3 formats] 64^3 u16 volume: TIFF slices -> HDF5 -> raw+JSON, mean {:.1f} (expected {:.1f})\n",
             st.mean, 10000 + 30000 * st.hist.back() / static_cast<double>(st.voxels));
}

// The synthetic stages, unless a previous demo left all five.
void stage_xct(const fs::path& dir, int64_t size) {
  bool all = true;
  for (int s = 0; s < 5; ++s) all = all && fs::exists(dir / ("xct_stage" + std::to_string(s) + ".h5"));
  if (all) {
    fmt::print("[2/3 xct] 5 synthetic zeolite stages: re-using {}\n", dir.string());
    return;
  }
  const auto t = clk::now();
  fs::create_directories(dir);
  tg::synth::Scene sc = tg::synth::preset_scene("zeolite-stages");
  tg::Config scene = tg::Config::from_string(kDemoScene, "examples/demo_scene.toml");
  tg::synth::apply_config(sc, scene);
  sc.size = size;
  sc.seed = 1;
  tg::synth::run_synth(sc, (dir / "xct.h5").string(), false);
  fmt::print("[2/3 xct] 5 synthetic zeolite stages at {}^3 in {:.1f} s\n", size, since(t));
}

int run_demo(const Opts& o) {
  const auto t0 = clk::now();
  const fs::path dir = fs::absolute(o.out);
  fs::create_directories(dir);

  stage_formats(dir);
  stage_xct(dir / ("scans_" + std::to_string(o.xct_size)), o.xct_size);

  tg::write_file_atomic(dir / "dem.toml", kDemoDem);
  tg::write_file_atomic(dir / "study.toml", demo_study(o.xct_size));
  fmt::print("[3/3 study] tomograin run {} -o {}\n", (dir / "study.toml").string(), (dir / "study").string());
  std::fflush(stdout);
  tg::app::run_command("run", {(dir / "study.toml").string(), "-o", (dir / "study").string()});

  const tg::Table sum = tg::read_csv(dir / "study" / "summary" / "summary.csv");
  fmt::print("demo finished in {:.1f} s; experiment vs DEM at {:.2f} % strain:\n", since(t0),
             100 * sum.num("final_strain").front());
  fmt::print("  D50 {:.3f} / {:.3f} mm, Cu {:.3f} / {:.3f}, intact grains broken {:.1f} / {:.1f} %, "
             "KS distance PSD {:.3f} FR {:.3f} AR {:.3f}; DEM yield {:.2f} MPa\n",
             sum.num("d50_mm_experiment").front(), sum.num("d50_mm_dem").front(), sum.num("cu_experiment").front(),
             sum.num("cu_dem").front(), sum.num("pct_broken_experiment").front(), sum.num("pct_broken_dem").front(),
             sum.num("psd_ks").front(), sum.num("fr_ks").front(), sum.num("ar_ks").front(),
             sum.num("yield_mpa_dem").front());
  const fs::path html = dir / "study" / "report" / "index.html";
  fmt::print("report: {}\n", (fs::exists(html) ? html : html.parent_path()).string());
  return 0;
}

}  // namespace cmd_demo

namespace cmd_demo {
static tg::app::Registrar reg{{"demo", 100,
      "Run the whole chain on a small embedded default and print where the report is:\n"
      "synthetic XCT loading stages (zeolite-stages preset, standing in for scans), then the demo\n"
      "study (OUT/study.toml, run by `tomograin run`): every stage analysed and tracked, a DEM\n"
      "oedometer with the study's breakage model, voxelisation of the DEM snapshots, the same\n"
      "segmentation and measurement on both, the validation report (index.html with PSD, FR, AR,\n"
      "stress-strain, broken grains, slices) and the study's summary. A few minutes on 2 cores;\n"
      "run again, it re-uses the scans and skips every step that is up to date.\n\n"
      "Example:\n  tomograin demo -o out/demo",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("-o,--output", o->out, "Output folder")->capture_default_str();
  sub->add_option("--xct-size", o->xct_size, "Edge of the synthetic scans in voxels (field 8.4 mm; 280 = 30 um voxels)")
      ->check(CLI::Range(64, 512))
      ->capture_default_str();
  return [o] { return run_demo(*o); };
}}};
}  // namespace cmd_demo

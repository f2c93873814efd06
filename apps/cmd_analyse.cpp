// tomograin analyse SCAN -o DIR: segment + measure + psd in one go, the same
// three jobs a user would run by hand (apps/jobs.hpp), on files in DIR.
#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "apps/command.hpp"
#include "apps/jobs.hpp"
#include "core/atomic_file.hpp"
#include "core/clock.hpp"
#include "core/memory.hpp"

namespace cmd_analyse {
namespace fs = std::filesystem;

struct Opts {
  std::string in, out;
  double voxel_um = 0, grain_diameter_um = 1360.0, grain_radius_vox = 0;
  std::string feret = "60";
  bool box = false;
  std::string memory_limit;  // segment's and measure's --memory-limit
};

// Each job's wall time and its own peak resident memory (the peak is reset
// before it where the kernel allows: see tg::reset_peak_rss), for
// DIR/analyse.json: what a user sizing a machine for a full scan needs.
struct StageCost {
  std::string name;
  double seconds = 0;
  int64_t peak_bytes = 0;
  bool own_peak = false;  // false: the process's peak so far
};
StageCost run_stage(const char* name, const std::function<void()>& job) {
  StageCost c{name};
  c.own_peak = tg::reset_peak_rss();
  const auto t0 = std::chrono::steady_clock::now();
  job();
  c.seconds = tg::seconds_since(t0);
  c.peak_bytes = tg::peak_rss_bytes();
  return c;
}

void write_costs(const fs::path& path, const fs::path& segment_summary, const std::vector<StageCost>& costs) {
  int64_t nvox = 0;  // the scan's voxel count, from segment's own summary
  if (std::ifstream f(segment_summary); f) {
    const auto s = nlohmann::json::parse(f, nullptr, false);
    if (s.is_object() && s.contains("shape") && s["shape"].is_array()) {
      nvox = 1;
      for (const auto& e : s["shape"]) nvox *= e.get<int64_t>();
    }
  }
  nlohmann::json j;
  j["voxels"] = nvox;
  double total = 0;
  int64_t peak = 0;
  for (const StageCost& c : costs) {
    j["stages"].push_back({{"name", c.name},
                           {"seconds", c.seconds},
                           {"peak_rss_bytes", c.peak_bytes},
                           {"peak_rss_bytes_per_voxel", nvox ? double(c.peak_bytes) / double(nvox) : 0.0},
                           {"peak_scope", c.own_peak ? "stage" : "process"}});
    total += c.seconds;
    peak = std::max(peak, c.peak_bytes);
  }
  j["seconds_total"] = total;
  j["peak_rss_bytes"] = peak;
  j["peak_rss_bytes_per_voxel"] = nvox ? double(peak) / double(nvox) : 0.0;
  tg::write_file_atomic(path.string(), j.dump(2) + "\n");
}

int run_analyse(const Opts& o) {
  // Build into a temporary folder beside DIR, rename at the end: a failed
  // analysis leaves no partial results folder.
  tg::AtomicPath out(fs::path(o.out).lexically_normal());
  fs::create_directories(out.temp());
  const fs::path d = out.temp();

  tg::app::SegmentJob seg;
  seg.in = o.in;
  seg.out = (d / "labels.h5").string();
  seg.voxel_um = o.voxel_um;
  seg.grain_diameter_um = o.grain_diameter_um;
  seg.grain_radius_vox = o.grain_radius_vox;
  // The labels stay in memory from segment to measure: reading them back
  // from labels.h5 cost ~23 s of decompression on a 1220^3 scan.
  tg::Volume<uint32_t> labels;
  seg.keep_labels = &labels;
  seg.memory_limit = o.memory_limit;
  std::vector<StageCost> costs;
  costs.push_back(run_stage("segment", [&] { tg::app::run_segment(seg); }));

  tg::app::MeasureJob mea;
  mea.in = seg.out;
  mea.out = {(d / "particles.csv").string()};
  mea.feret = o.feret;
  mea.grey = o.in;  // volumes from the grey levels (measure/grey_volume.hpp)
  mea.voxel_um = o.voxel_um;
  mea.box = o.box;
  // Segmented slab by slab, the labels are only in labels.h5: measure reads
  // them from there (slab by slab too when they do not fit).
  mea.labels = labels.size() ? &labels : nullptr;
  mea.memory_limit = o.memory_limit;
  costs.push_back(run_stage("measure", [&] { tg::app::run_measure(mea); }));
  labels = tg::Volume<uint32_t>();

  tg::app::PsdJob psd;
  psd.in = {mea.out[0]};
  psd.names = {(fs::path(o.out) / "particles.csv").string()};  // where it will be, not the temporary folder
  psd.out = (d / "psd.csv").string();
  costs.push_back(run_stage("psd", [&] { tg::app::run_psd(psd); }));
  write_costs(d / "analyse.json", d / "labels.segment.json", costs);

  out.commit();
  fmt::print("analysis of {} in {}: labels.h5, labels.segment.json, particles.csv, psd.csv, psd_summary.csv, "
             "analyse.json\n", o.in, o.out);
  for (const StageCost& c : costs)
    fmt::print("  {:8s} {:8.2f} s, peak memory {}\n", c.name, c.seconds, tg::human_bytes(double(c.peak_bytes)));
  return 0;
}

}  // namespace cmd_analyse

namespace cmd_analyse {
static tg::app::Registrar reg{{"analyse", 50,
      "Segment a scan, measure every particle and compute its grading, in one go:\n"
      "the jobs of `segment`, `measure --grey SCAN` (volumes from the scan's grey levels) and `psd` with\n"
      "their defaults (run those for every option).\n"
      "Writes DIR/labels.h5 (+ labels.segment.json), DIR/particles.csv, DIR/psd.csv and\n"
      "DIR/psd_summary.csv (D10/D50/D60/Cu, FR and AR classes) and DIR/analyse.json (each step's wall\n"
      "time and peak memory, bytes and bytes per voxel). DIR appears only when all succeed.\n\n"
      "Examples:\n"
      "  tomograin analyse stage0.h5 -o results/stage0\n"
      "  tomograin analyse slices/ -o results/stage3 --voxel-um 12.3 --feret exact\n"
      "  tomograin analyse scan2048.h5:/scan -o results/big --memory-limit 16GiB",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("scan", o->in, "Grey scan (uint16, float32 is normalised; any volume format)")->required();
  sub->add_option("-o,--output", o->out, "Results folder (must not be the input's folder)")->required();
  tg::app::add_voxel_option(sub, o->voxel_um);
  sub->add_option("--grain-diameter-um", o->grain_diameter_um, "Expected grain diameter, micrometres (sets the scale)")
      ->capture_default_str();
  sub->add_option("--grain-radius-vox", o->grain_radius_vox, "Expected grain radius in voxels (overrides the diameter)");
  sub->add_option("--feret", o->feret, "Feret orientations N, or 'exact'")->capture_default_str();
  sub->add_flag("--box", o->box, "Also compute CGAL's oriented box (obb_* columns; slow on large scans)");
  sub->add_option("--memory-limit", o->memory_limit,
                  "Memory to stay under, e.g. 16GiB: a uint16 scan (any format) over it is segmented and measured slab by slab "
                  "with the same labels and table; see segment and measure --help");
  return [o] { return run_analyse(*o); };
}}};
}  // namespace cmd_analyse

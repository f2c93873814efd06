// tomograin analyse SCAN -o DIR: segment + measure + psd in one go, the same
// three jobs a user would run by hand (apps/jobs.hpp), on files in DIR.
#include <fmt/core.h>

#include <filesystem>

#include "apps/command.hpp"
#include "apps/jobs.hpp"
#include "core/atomic_file.hpp"

namespace cmd_analyse {
namespace fs = std::filesystem;

struct Opts {
  std::string in, out;
  double voxel_um = 0, grain_diameter_um = 1360.0, grain_radius_vox = 0;
  std::string feret = "60";
  bool box = false;
};

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
  tg::app::run_segment(seg);

  tg::app::MeasureJob mea;
  mea.in = seg.out;
  mea.out = {(d / "particles.csv").string()};
  mea.feret = o.feret;
  mea.grey = o.in;  // volumes from the grey levels (measure/grey_volume.hpp)
  mea.voxel_um = o.voxel_um;
  mea.box = o.box;
  tg::app::run_measure(mea);

  tg::app::PsdJob psd;
  psd.in = {mea.out[0]};
  psd.names = {(fs::path(o.out) / "particles.csv").string()};  // where it will be, not the temporary folder
  psd.out = (d / "psd.csv").string();
  tg::app::run_psd(psd);

  out.commit();
  fmt::print("analysis of {} in {}: labels.h5, labels.segment.json, particles.csv, psd.csv, psd_summary.csv\n", o.in,
             o.out);
  return 0;
}

}  // namespace cmd_analyse

namespace cmd_analyse {
static tg::app::Registrar reg{{"analyse", 50,
      "Segment a scan, measure every particle and compute its grading, in one go:\n"
      "the jobs of `segment`, `measure --grey SCAN` (volumes from the scan's grey levels) and `psd` with\n"
      "their defaults (run those for every option).\n"
      "Writes DIR/labels.h5 (+ labels.segment.json), DIR/particles.csv, DIR/psd.csv and\n"
      "DIR/psd_summary.csv (D10/D50/D60/Cu, FR and AR classes). DIR appears only when all succeed.\n\n"
      "Examples:\n"
      "  tomograin analyse stage0.h5 -o results/stage0\n"
      "  tomograin analyse slices/ -o results/stage3 --voxel-um 12.3 --feret exact",
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
  return [o] { return run_analyse(*o); };
}}};
}  // namespace cmd_analyse

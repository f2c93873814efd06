#include "compare/dem_stage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>

#include "compare/report_files.hpp"
#include "compare/voxelise.hpp"
#include "core/errors.hpp"
#include "dem/run_folder.hpp"

namespace tg::compare {
namespace fs = std::filesystem;
using json = nlohmann::json;

DemInputs load_dem_inputs(const CompareInputs& in) {
  DemInputs d;
  if (!in.dem_snapshots.empty()) {
    d.snapshots = in.dem_snapshots;
    if (!in.dem_strains.empty() && in.dem_strains.size() != d.snapshots.size())
      throw UsageError("compare: " + std::to_string(d.snapshots.size()) + " DEM snapshots but " +
                       std::to_string(in.dem_strains.size()) + " strains");
    d.strains = in.dem_strains.empty() ? std::vector<double>(d.snapshots.size(), std::numeric_limits<double>::quiet_NaN())
                                       : in.dem_strains;
    if (!in.dem_run.empty() && fs::exists(fs::path(in.dem_run) / "history.csv"))
      d.history = history_curve(read_csv(fs::path(in.dem_run) / "history.csv"));
    return d;
  }
  const dem::RunFolder run = dem::read_run_folder(in.dem_run);
  for (size_t k = 0; k < run.snapshots.size(); ++k) {
    d.snapshots.push_back(run.snapshot_path(k).string());
    d.strains.push_back(run.snapshots[k].axial_strain);
  }
  if (!in.dem_strains.empty()) {
    if (in.dem_strains.size() != d.snapshots.size())
      throw UsageError("compare: " + std::to_string(d.snapshots.size()) + " DEM snapshots but " +
                       std::to_string(in.dem_strains.size()) + " strains");
    d.strains = in.dem_strains;
  }
  d.history = history_curve(run.history);
  return d;
}

ParticleScale particle_scale(const SphereTable& s) {
  std::map<int64_t, double> vol;
  for (size_t q = 0; q < s.size(); ++q) vol[s.particle[q]] += std::pow(s.r_m[q], 3);
  std::vector<double> r;
  for (const auto& [id, v] : vol) r.push_back(std::cbrt(v));  // equal-volume sphere radius
  std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2), r.end());
  return {r[r.size() / 2], static_cast<int64_t>(vol.size())};
}

double sphere_coordination(const SphereTable& s, double gap_tolerance) {
  double rmax = 0;
  for (double r : s.r_m) rmax = std::max(rmax, r);
  const double cell = 2 * rmax * (1 + gap_tolerance);
  auto key = [&](int64_t a, int64_t b, int64_t c) { return (a * 1000003 + b) * 1000033 + c; };
  auto idx = [&](double v) { return static_cast<int64_t>(std::floor(v / cell)); };
  std::unordered_map<int64_t, std::vector<size_t>> grid;
  for (size_t q = 0; q < s.size(); ++q) grid[key(idx(s.z_m[q]), idx(s.y_m[q]), idx(s.x_m[q]))].push_back(q);
  std::set<std::pair<int64_t, int64_t>> pairs;  // particle ids, ordered: each contact once
  for (size_t q = 0; q < s.size(); ++q) {
    const int64_t cz = idx(s.z_m[q]), cy = idx(s.y_m[q]), cx = idx(s.x_m[q]);
    for (int64_t dz = -1; dz <= 1; ++dz)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dx = -1; dx <= 1; ++dx) {
          const auto it = grid.find(key(cz + dz, cy + dy, cx + dx));
          if (it == grid.end()) continue;
          for (size_t p : it->second) {
            if (p <= q || s.particle[p] == s.particle[q]) continue;
            const double d = std::hypot(s.z_m[p] - s.z_m[q], s.y_m[p] - s.y_m[q], s.x_m[p] - s.x_m[q]);
            if (d <= s.r_m[p] + s.r_m[q] + gap_tolerance * std::min(s.r_m[p], s.r_m[q]))
              pairs.insert(std::minmax(s.particle[p], s.particle[q]));
          }
        }
  }
  const int64_t n = particle_count(s);
  return n ? 2.0 * static_cast<double>(pairs.size()) / static_cast<double>(n) : 0.0;
}

DemStage image_snapshot(const std::string& snapshot, double voxel_m, const synth::ImagingOptions& imaging,
                        const std::string& imaging_from, const CompareOptions& opt, const SegmentOptions& so,
                        const fs::path& slices, const std::string& stem) {
  VoxeliseOptions vo = opt.voxelise;
  vo.voxel_m = voxel_m;
  vo.grey = opt.imaged_path;
  vo.imaging = imaging;
  const SphereTable spheres = read_spheres(snapshot);
  Voxelised v = voxelise(spheres, vo);
  DemStage d;
  d.exact_coordination = sphere_coordination(spheres);
  d.particles = static_cast<int64_t>(v.particle_of_label.size()) - 1;
  d.ideal.particles = measure_labels(v.labels, opt.measure);
  d.ideal.sample = measure::grading_sample(d.ideal.particles);
  d.ideal.coordination = mean_interior_coordination(d.ideal.particles);
  write_mid_slices(v.labels, slices, stem + "_dem_ideal_labels");
  if (opt.imaged_path) {
    write_mid_slices(v.grey, slices, stem + "_dem_grey");
    SegmentResult r = segment(std::move(v.grey), so);
    d.imaged.info["segment"] = json::parse(summary_json(r, so), nullptr, false);
    write_mid_slices(r.labels, slices, stem + "_dem_imaged_labels");
    d.imaged.particles = measure_labels(r.labels, opt.measure);
    d.imaged.sample = measure::grading_sample(d.imaged.particles);
    d.imaged.coordination = mean_interior_coordination(d.imaged.particles);
  }
  d.ideal.info["voxelise"] = voxelise_json(snapshot, vo, v, imaging_from);
  d.ideal.info["voxelise"]["render_s"] = v.render_s;
  d.ideal.info["voxelise"]["imaging_s"] = v.imaging_s;
  d.ideal.info["exact_coordination"] = d.exact_coordination;  // from the spheres: the image method's reference
  return d;
}

}  // namespace tg::compare

#include "compare/dem_stage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <unordered_map>

#include "compare/report_files.hpp"
#include "compare/voxelise.hpp"
#include "measure/feret.hpp"
#include "measure/hull.hpp"
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

namespace {
// Equal-volume sphere radius of each particle id: cbrt of the sum of its
// spheres' r^3 (fragment spheres are tangent, not overlapping).
std::map<int64_t, double> equal_volume_radius(const SphereTable& s) {
  std::map<int64_t, double> vol;
  for (size_t q = 0; q < s.size(); ++q) vol[s.particle[q]] += std::pow(s.r_m[q], 3);
  for (auto& [id, v] : vol) v = std::cbrt(v);
  return vol;
}
}  // namespace

ParticleScale particle_scale(const SphereTable& s) {
  const std::map<int64_t, double> req = equal_volume_radius(s);
  std::vector<double> r;
  for (const auto& [id, v] : req) r.push_back(v);
  std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2), r.end());
  return {r[r.size() / 2], static_cast<int64_t>(req.size())};
}

std::vector<SphereContact> sphere_contacts(const SphereTable& s, double gap_tolerance) {
  double rmax = 0;
  for (double r : s.r_m) rmax = std::max(rmax, r);
  const double cell = 2 * rmax * (1 + gap_tolerance);
  auto key = [&](int64_t a, int64_t b, int64_t c) { return (a * 1000003 + b) * 1000033 + c; };
  auto idx = [&](double v) { return static_cast<int64_t>(std::floor(v / cell)); };
  std::unordered_map<int64_t, std::vector<size_t>> grid;
  for (size_t q = 0; q < s.size(); ++q) grid[key(idx(s.z_m[q]), idx(s.y_m[q]), idx(s.x_m[q]))].push_back(q);
  std::vector<std::pair<size_t, size_t>> found;  // sphere indices q < p
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
            if (d <= s.r_m[p] + s.r_m[q] + gap_tolerance * std::min(s.r_m[p], s.r_m[q])) found.emplace_back(q, p);
          }
        }
  }
  std::sort(found.begin(), found.end());  // the grid's visiting order is not the index order
  std::vector<SphereContact> out;
  for (auto [q, p] : found) {
    if (s.particle[q] > s.particle[p]) std::swap(q, p);  // from the smaller particle id to the larger
    const Eigen::Vector3d d(s.z_m[p] - s.z_m[q], s.y_m[p] - s.y_m[q], s.x_m[p] - s.x_m[q]);
    out.push_back({s.particle[q], s.particle[p], d.normalized()});
  }
  return out;
}

namespace {
// Number of distinct particles each particle touches (every particle of the table, zeros included).
std::map<int64_t, int> particle_coordination(const SphereTable& s, const std::vector<SphereContact>& contacts) {
  std::map<int64_t, int> z;
  for (int64_t id : s.particle) z[id] = 0;
  std::set<std::pair<int64_t, int64_t>> pairs;
  for (const auto& c : contacts)
    if (pairs.emplace(c.a, c.b).second) ++z[c.a], ++z[c.b];
  return z;
}
}  // namespace

ContactSeries exact_contact_series(const SphereTable& s, double gap_tolerance) {
  const std::vector<SphereContact> contacts = sphere_contacts(s, gap_tolerance);
  std::vector<std::pair<int64_t, int64_t>> pairs;
  std::vector<Eigen::Vector3d> normals;
  for (const auto& c : contacts) {
    pairs.emplace_back(c.a, c.b);
    normals.push_back(c.normal);
  }
  ContactSeries out = contact_series(pairs, normals);
  const std::map<int64_t, double> req = equal_volume_radius(s);
  std::vector<double> d_eq_mm, coord;
  for (const auto& [id, n] : particle_coordination(s, contacts)) {
    d_eq_mm.push_back(2e3 * req.at(id));
    coord.push_back(n);
  }
  out.by_size = measure::coordination_by_size(d_eq_mm, coord);
  return out;
}

measure::GradingSample exact_shape_sample(const SphereTable& s) {
  std::map<int64_t, std::vector<size_t>> members;
  for (size_t q = 0; q < s.size(); ++q) members[s.particle[q]].push_back(q);
  std::vector<const std::vector<size_t>*> groups;
  for (const auto& [id, m] : members) groups.push_back(&m);
  // Points on a sphere: the golden-spiral half-sphere and its mirror image, pushed out so that
  // their hull has the sphere's volume (the inscribed polytope of 256 points holds 1.6 % less):
  // calipers then read between -0.1 % and +0.6 % of the radius instead of -0.6 % to 0.
  std::vector<measure::Vec3> unit = measure::half_sphere_directions(128);
  for (size_t q = 0, n = unit.size(); q < n; ++q) unit.push_back(-unit[q]);
  const double scale = std::cbrt(4.0 / 3.0 * std::numbers::pi / measure::hull_volume(measure::convex_hull(unit)));
  for (auto& u : unit) u *= scale;
  const int64_t n = static_cast<int64_t>(groups.size());
  std::vector<double> dmed(n), vol(n), deq(n), fr(n), ar(n);
#pragma omp parallel for schedule(dynamic, 16)
  for (int64_t g = 0; g < n; ++g) {
    const std::vector<size_t>& m = *groups[static_cast<size_t>(g)];
    double vs = 0;
    for (size_t q : m) vs += 4.0 / 3.0 * std::numbers::pi * std::pow(s.r_m[q], 3);
    deq[g] = 1e3 * std::cbrt(6.0 * vs / std::numbers::pi);
    if (m.size() == 1) {  // a sphere: every caliper is its diameter
      dmed[g] = deq[g], vol[g] = 1e9 * vs, fr[g] = 1, ar[g] = 1;
      continue;
    }
    // Millimetres about the first sphere's centre: small coordinates for the hull's predicates.
    const measure::Vec3 o(s.z_m[m[0]], s.y_m[m[0]], s.x_m[m[0]]);
    std::vector<measure::Vec3> pts;
    pts.reserve(m.size() * unit.size());
    for (size_t q : m) {
      const measure::Vec3 c = (measure::Vec3(s.z_m[q], s.y_m[q], s.x_m[q]) - o) * 1e3;
      for (const auto& u : unit) pts.push_back(c + 1e3 * s.r_m[q] * u);
    }
    const measure::ConvexHull hull = measure::convex_hull(pts);
    measure::Particle p;
    // The tie rule as the particle table uses it (tolerance there: half a voxel, ~1 % of a grain's
    // Dmax): a fragment's diameters form a ring (its 8 outer spheres), and the single longest pair
    // of the sampled surfaces tilts out of the flat face by a few degrees, which moved its Dmin, so
    // its AR and FR, by up to 0.1 with the fragment's turn (tests/compare/exact_shapes_test.cpp).
    measure::FeretExactOptions fo;
    fo.tie_tolerance = 0.01 * measure::hull_diameter(hull);
    p.feret = measure::feret_exact(hull, fo);
    p.stats.volume_m3 = measure::hull_volume(hull);  // mm^3 here: fill_sizing only takes ratios
    measure::fill_sizing(p, measure::Sizing::feret);
    dmed[g] = p.d_med_m, vol[g] = p.stats.volume_m3, fr[g] = p.fr, ar[g] = p.ar;
  }
  measure::GradingSample out;
  out.size_mm = std::move(dmed);
  out.mass = std::move(vol);
  out.deq_mm = std::move(deq);
  out.fr = std::move(fr);
  out.ar = std::move(ar);
  return out;
}

DemStage image_snapshot(const std::string& snapshot, double voxel_m, const synth::ImagingOptions& imaging,
                        const std::string& imaging_from, const CompareOptions& opt, const SegmentOptions& so,
                        const fs::path& slices, const std::string& stem, bool keep_labels) {
  VoxeliseOptions vo = opt.voxelise;
  vo.voxel_m = voxel_m;
  vo.grey = opt.imaged_path;
  vo.imaging = imaging;
  const SphereTable spheres = read_spheres(snapshot);
  Voxelised v = voxelise(spheres, vo);
  DemStage d;
  d.exact = exact_contact_series(spheres);
  d.exact_shapes = exact_shape_sample(spheres);
  d.exact_coordination = mean_coordination(d.exact.by_size);
  d.particles = static_cast<int64_t>(v.particle_of_label.size()) - 1;
  measure_series(v.labels, opt.measure, d.ideal);
  write_mid_slices(v.labels, slices, stem + "_dem_ideal_labels");
  d.ideal.info["voxelise"] = voxelise_json(snapshot, vo, v, imaging_from);
  d.ideal.info["voxelise"]["render_s"] = v.render_s;
  d.ideal.info["voxelise"]["imaging_s"] = v.imaging_s;
  d.ideal.info["exact_coordination"] = d.exact_coordination;  // from the spheres: the image method's reference
  // The imaged path does not read the truth labels: kept only when asked,
  // else freed before segmenting (4 B/voxel off its peak; at the study's
  // 12.3 um a snapshot is ~1.4e9 voxels, and a full-size compare ran out of
  // memory with them held).
  if (keep_labels) {
    d.truth_labels = std::move(v.labels);
    d.particle_of_label = std::move(v.particle_of_label);
  } else {
    v.labels = Volume<uint32_t>();
  }
  if (opt.imaged_path) {
    write_mid_slices(v.grey, slices, stem + "_dem_grey");
    // Measured as the XCT stages are: volumes from the grey levels.
    SegmentResult r = segment(v.grey, so);
    d.imaged.info["segment"] = json::parse(summary_json(r, so), nullptr, false);
    write_mid_slices(r.labels, slices, stem + "_dem_imaged_labels");
    measure_series(r.labels, opt.measure, d.imaged, &v.grey);
    v.grey = Volume<uint16_t>();
    if (keep_labels) d.imaged_labels = std::move(r.labels);
  }
  return d;
}

}  // namespace tg::compare

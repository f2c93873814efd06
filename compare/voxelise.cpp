#include "compare/voxelise.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "data_synth/truth.hpp"

namespace tg::compare {

std::pair<Shape, Geometry> voxel_grid(const SphereTable& s, const VoxeliseOptions& opt) {
  if (!(opt.voxel_m > 0) || !std::isfinite(opt.voxel_m)) throw UsageError("voxelise: voxel size must be > 0");
  if (!(opt.margin_vox >= 0)) throw UsageError("voxelise: margin must be >= 0 voxels");
  if (s.size() == 0) throw InputError(s.source + ": no spheres");
  // lo/hi in (z, y, x), metres.
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::max();
    hi[a] = std::numeric_limits<double>::lowest();
  }
  for (size_t q = 0; q < s.size(); ++q) {
    const double c[3] = {s.z_m[q], s.y_m[q], s.x_m[q]};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a] - s.r_m[q]);
      hi[a] = std::max(hi[a], c[a] + s.r_m[q]);
    }
  }
  if (opt.field == FieldOfView::cylinder) {
    if (!(opt.cylinder_diameter_m > 0)) throw UsageError("voxelise: cylinder diameter must be > 0");
    const double half = 0.5 * opt.cylinder_diameter_m;
    lo[0] = std::min(lo[0], 0.0);  // the bottom platen
    lo[1] = lo[2] = -half;
    hi[1] = hi[2] = half;
  }
  const double m = opt.margin_vox * opt.voxel_m;
  int64_t n[3];
  Geometry g = Geometry::isotropic_m(opt.voxel_m);
  for (int a = 0; a < 3; ++a) {
    lo[a] -= m;
    hi[a] += m;
    const double cells = std::ceil((hi[a] - lo[a]) / opt.voxel_m - 1e-9);
    if (!(cells >= 1) || cells > 8192)
      throw InputError(s.source + ": field of view of " + std::to_string(cells) +
                       " voxels along an axis (allowed 1..8192): check the voxel size and units (metres)");
    n[a] = static_cast<int64_t>(cells);
    // Centre the grid on the field so the margin is the same on both sides.
    g.origin_m[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * static_cast<double>(n[a]) * opt.voxel_m;
  }
  return {Shape{n[0], n[1], n[2]}, g};
}

namespace {

// True when no two member spheres penetrate deeper than tol × the smaller radius.
bool members_disjoint(const synth::Piece* begin, const synth::Piece* end, double tol) {
  if (tol < 0) return false;
  for (const synth::Piece* a = begin; a != end; ++a)
    for (const synth::Piece* b = a + 1; b != end; ++b) {
      const double d = std::hypot(a->sphere.c[0] - b->sphere.c[0], a->sphere.c[1] - b->sphere.c[1],
                                  a->sphere.c[2] - b->sphere.c[2]);
      if (a->sphere.r + b->sphere.r - d > tol * std::min(a->sphere.r, b->sphere.r)) return false;
    }
  return true;
}

}  // namespace

Voxelised voxelise(const SphereTable& s, const VoxeliseOptions& opt) {
  const auto [shape, geom] = voxel_grid(s, opt);
  Voxelised out;
  const std::vector<synth::Particle> particles = synth::particles_from_spheres(s, geom, &out.particle_of_label);
  // What the renderer gets: clusters with disjoint members as separate spheres
  // (render ids 1..n), with label_of[render id] = particle label.
  std::vector<synth::Particle> render_list;
  std::vector<uint32_t> label_of{0};
  bool split_any = false;
  for (const synth::Particle& p : particles) {
    const bool split = p.kind == synth::Kind::cluster && p.pieces.size() <= 256 &&
                       members_disjoint(p.pieces.data(), p.pieces.data() + p.pieces.size(), opt.member_overlap);
    if (p.kind == synth::Kind::cluster) ++(split ? out.clusters_split : out.clusters_union);
    if (!split) {
      synth::Particle q = p;
      q.id = static_cast<uint32_t>(label_of.size());
      render_list.push_back(std::move(q));
      label_of.push_back(p.id);
      continue;
    }
    split_any = true;
    for (const synth::Piece& piece : p.pieces) {
      render_list.push_back(synth::make_grain(static_cast<uint32_t>(label_of.size()), piece.sphere.c, piece.sphere.r));
      label_of.push_back(p.id);
    }
  }
  if (label_of.size() >= std::numeric_limits<uint32_t>::max()) throw InputError(s.source + ": too many spheres");
  auto t0 = std::chrono::steady_clock::now();
  synth::RenderOptions ro = opt.render;
  ro.labels = true;
  synth::Rendered r = synth::render(render_list, shape, geom, ro);
  if (split_any) {
    uint32_t* lab = r.labels.data();
    const int64_t n = r.labels.size();
#pragma omp parallel for schedule(static)
    for (int64_t q = 0; q < n; ++q) lab[q] = label_of[lab[q]];
  }
  out.render_s = seconds_since(t0);
  out.solid_fraction = synth::mean_solid_fraction(r.solid);
  if (opt.truth) {
    out.truth = synth::truth_table(particles, r.labels, shape, geom);
    std::vector<double> pid(out.particle_of_label.begin() + 1, out.particle_of_label.end());
    out.truth.add("particle", std::move(pid));
  }
  if (opt.grey) {
    t0 = std::chrono::steady_clock::now();
    synth::apply_imaging(r.solid, opt.imaging);
    synth::U16Result u = synth::to_u16(r.solid);
    out.saturated = u.saturated_low + u.saturated_high;
    out.grey = std::move(u.volume);
    out.grey.set_geometry(geom);
    out.imaging_s = seconds_since(t0);
  }
  out.labels = std::move(r.labels);
  out.labels.set_geometry(geom);
  return out;
}

nlohmann::json voxelise_json(const std::string& input, const VoxeliseOptions& opt, const Voxelised& v,
                             const std::string& imaging_from) {
  const Shape s = v.labels.shape();
  return {{"input", input},
          {"voxel_um", opt.voxel_m * 1e6},
          {"shape", {s.nz, s.ny, s.nx}},
          {"solid_fraction", v.solid_fraction},
          {"void_grey", opt.imaging.void_grey},
          {"solid_grey", opt.imaging.solid_grey},
          {"noise_sigma", opt.imaging.noise_sigma},
          {"psf_sigma_vox", opt.imaging.psf_sigma},
          {"imaging_from", opt.grey ? imaging_from : std::string("no grey scan (labels only)")}};
}

}  // namespace tg::compare

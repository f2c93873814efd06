#include "measure/particles.hpp"

#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "measure/feret.hpp"

namespace tg::measure {

double hull_volume(const ConvexHull& hull) {
  if (hull.dimension < 3 || hull.faces.empty()) return 0.0;
  Vec3 c = Vec3::Zero();
  for (const auto& v : hull.vertices) c += v;
  c /= static_cast<double>(hull.vertices.size());
  // Summed in sorted order: CGAL's hull may list (and split coplanar facets
  // into) triangles in an order that depends on its per-thread random state,
  // and the table must not depend on the thread count.
  std::vector<double> t;
  t.reserve(hull.faces.size());
  for (const auto& f : hull.faces)
    t.push_back(std::abs((hull.vertices[f[0]] - c).dot((hull.vertices[f[1]] - c).cross(hull.vertices[f[2]] - c))));
  std::sort(t.begin(), t.end());
  double vol = 0;
  for (double x : t) vol += x;
  return vol / 6.0;
}

void fill_sizing(Particle& p, Sizing sizing) {
  if (sizing == Sizing::obb) {
    p.d_min_m = p.box.dims[0];
    p.d_med_m = p.box.dims[1];
    p.d_max_m = p.box.dims[2];
  } else {
    p.d_max_m = p.feret.d_max;
    p.d_min_m = p.feret.d_min;
    const double den = std::numbers::pi * p.d_max_m * p.d_min_m;
    p.d_med_m = den > 0 ? 6.0 * p.stats.volume_m3 / den : 0.0;
  }
  // FR > 1 cannot happen on a convex particle (Dmed >= Dmin there) but does
  // on hollow or concave ones, whose volume is below the Dmax x Dmin x Dmin
  // ellipsoid's: FR is clamped to 1 and the row flagged (header).
  const double fr = p.d_med_m > 0 ? p.d_min_m / p.d_med_m : 0.0;
  p.fr_clamped = fr > 1.0;
  p.fr = std::min(fr, 1.0);
  p.ar = p.d_min_m > 0 ? p.d_max_m / p.d_min_m : 0.0;
}

namespace {

void check_particle_options(const ParticleOptions& opt) {
  if (!opt.feret_exact && opt.feret_directions < 3)
    throw UsageError("Feret orientations must be >= 3 (or exact), got " + std::to_string(opt.feret_directions));
  if (opt.sizing == Sizing::obb && !opt.oriented_box)
    throw UsageError("sizing = obb needs the oriented box");
  // Checked here, not in the parallel loop below: an exception cannot leave an OpenMP region.
  if (!(opt.face_offset > 0 && opt.face_offset <= 1))
    throw UsageError("--face-offset must be in (0, 1], got " + std::to_string(opt.face_offset));
}

}  // namespace

std::vector<Particle> measure_particles(const VolumeView<const uint32_t>& labels, const ParticleOptions& opt) {
  check_particle_options(opt);
  LabelStatsOptions so = opt.stats;
  so.collect_surface = true;
  so.threads = opt.threads;
  const LabelStatsResult ls = label_stats(labels, so);
  std::vector<double> grey_vox;  // aligned with ls.labels; empty without a grey scan
  if (opt.grey || opt.grey_slabs) {
    GreyVolumeOptions go = opt.grey_levels;
    go.threads = opt.threads;
    std::vector<uint32_t> ids;
    for (const LabelStats& st : ls.labels) ids.push_back(st.label);
    grey_vox = opt.grey ? grey_volumes(labels, *opt.grey, ids, go)
                        : grey_volumes(labels, *opt.grey_slabs, ids, go, grey_window_slices(labels.shape()));
  }
  std::vector<Particle> out = particles_from_stats(ls, grey_vox, labels.geometry(), opt, &labels);
  if (opt.contacts) {
    ContactOptions co = opt.contact;
    co.threads = opt.threads;
    const auto res = find_contacts(labels, co);
    std::vector<uint32_t> ids;
    ids.reserve(out.size());
    for (const auto& P : out) ids.push_back(P.stats.label);
    const auto z = coordination(res.contacts, ids);
    for (size_t p = 0; p < out.size(); ++p) out[p].coordination = z[p];
  }
  return out;
}

std::vector<Particle> particles_from_stats(const LabelStatsResult& ls, const std::vector<double>& grey_vox,
                                           const Geometry& geometry, const ParticleOptions& opt,
                                           const VolumeView<const uint32_t>* labels) {
  check_particle_options(opt);
  if (opt.surface && !labels) throw UsageError("surface areas need the whole label volume");
  if (!grey_vox.empty() && grey_vox.size() != ls.labels.size())
    throw UsageError("grey volumes: " + std::to_string(grey_vox.size()) + " for " + std::to_string(ls.labels.size()) +
                     " labels");
  const auto dirs = opt.feret_exact ? std::vector<Vec3>{} : half_sphere_directions(opt.feret_directions);
  const auto& h = geometry.voxel_size_m;
  FeretExactOptions exact;
  exact.tie_tolerance = opt.tie_tolerance_voxels * std::max({h[0], h[1], h[2]});
  FeretSampledOptions sampled;
  sampled.tie_tolerance = exact.tie_tolerance;

  const bool need_hull = opt.feret_exact || opt.oriented_box || opt.convex || opt.force_hull;
  std::vector<Particle> out(ls.labels.size());
  const int64_t n = static_cast<int64_t>(out.size());
  const int nt = opt.threads > 0 ? opt.threads : 0;
  // Dynamic schedule: particle costs vary 1000-fold; each particle's result
  // depends only on its own voxels, so the order of work does not matter.
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt > 0 ? nt : omp_get_max_threads())
  for (int64_t p = 0; p < n; ++p) {
    Particle& P = out[static_cast<size_t>(p)];
    P.stats = ls.labels[static_cast<size_t>(p)];
    if (!grey_vox.empty()) {
      const auto& e = geometry.voxel_size_m;
      // Floor: a labelled voxel lies above a threshold near half contrast,
      // so it is about half solid at least; noise in the shell of a
      // one-voxel speck must not give it a volume of zero or less.
      P.grey_volume_m3 = std::max(grey_vox[size_t(p)], 0.5 * double(P.stats.voxels)) * e[0] * e[1] * e[2];
    }
    auto pts = caliper_points(ls.surface_of(static_cast<size_t>(p)), h, P.stats.box_lo, opt.face_offset);
    if (need_hull) {
      const ConvexHull hull = convex_hull(pts);
      P.hull_vertices = static_cast<int>(hull.vertices.size());
      P.feret = opt.feret_exact ? feret_exact(hull, exact) : feret_sampled(hull, dirs, sampled);
      if (opt.convex) {
        P.convex_volume_m3 = hull_volume(hull);
        P.solidity = P.convex_volume_m3 > 0 ? std::min(1.0, P.stats.volume_m3 / P.convex_volume_m3) : 1.0;
      }
      if (opt.oriented_box) P.box = oriented_box(hull.vertices, opt.obb);
    } else {
      // Sampled calipers need no hull: the width of a point set along u is
      // its hull's (the extremes are hull vertices), so the points go to
      // feret_sampled as they are (it reads only the vertex list). Same
      // numbers as through the hull up to the rounding of a dot product
      // (tests: ParticlesFastPath).
      ConvexHull points;
      points.vertices = std::move(pts);
      P.feret = feret_sampled(points, dirs, sampled);
    }
    if (opt.surface) {
      P.surface_m2 = surface_area(*labels, P.stats.label, ls.surface_of(static_cast<size_t>(p)), opt.surface_opt);
      P.sphericity = wadell_sphericity(P.stats.volume_m3, P.surface_m2);
    }
    fill_sizing(P, opt.sizing);
  }
  return out;
}

std::string sizing_name(const ParticleOptions& opt) {
  if (opt.sizing == Sizing::obb) return "obb";
  return opt.feret_exact ? "feret-exact" : "feret-" + std::to_string(opt.feret_directions);
}

Table particle_table(const std::vector<Particle>& ps) {
  Table t;
  auto col = [&](const std::string& name, auto f) {
    std::vector<double> v;
    v.reserve(ps.size());
    for (const auto& p : ps) v.push_back(static_cast<double>(f(p)));
    t.add(name, std::move(v));
  };
  constexpr double mm = 1e3, mm3 = 1e9, mm5 = 1e15;
  col("label", [](const Particle& p) { return p.stats.label; });
  col("voxels", [](const Particle& p) { return p.stats.voxels; });
  // volume_mm3 and d_eq_mm: the grey-level volume where there is one (the
  // unbiased estimate), else the label's; the label's own stays beside it.
  col("volume_mm3", [&](const Particle& p) { return p.volume_m3() * mm3; });
  col("cx_mm", [&](const Particle& p) { return p.stats.centroid_m[2] * mm; });
  col("cy_mm", [&](const Particle& p) { return p.stats.centroid_m[1] * mm; });
  col("cz_mm", [&](const Particle& p) { return p.stats.centroid_m[0] * mm; });
  col("d_eq_mm", [&](const Particle& p) { return std::cbrt(6.0 * p.volume_m3() / std::numbers::pi) * mm; });
  col("d_max_mm", [&](const Particle& p) { return p.d_max_m * mm; });
  col("d_min_mm", [&](const Particle& p) { return p.d_min_m * mm; });
  col("d_med_mm", [&](const Particle& p) { return p.d_med_m * mm; });
  col("fr", [](const Particle& p) { return p.fr; });
  col("ar", [](const Particle& p) { return p.ar; });
  col("fr_clamped", [](const Particle& p) { return p.fr_clamped ? 1 : 0; });
  col("obb_max_mm", [&](const Particle& p) { return p.box.dims[2] * mm; });
  col("obb_med_mm", [&](const Particle& p) { return p.box.dims[1] * mm; });
  col("obb_min_mm", [&](const Particle& p) { return p.box.dims[0] * mm; });
  col("touches_border", [](const Particle& p) { return p.stats.touches_border ? 1 : 0; });
  col("below_limit", [](const Particle& p) { return p.stats.below_limit ? 1 : 0; });
  col("feret_dmax_mm", [&](const Particle& p) { return p.feret.d_max * mm; });
  col("feret_dmin_mm", [&](const Particle& p) { return p.feret.d_min * mm; });
  col("feret_dmin_any_mm", [&](const Particle& p) { return p.feret.d_min_any * mm; });
  col("hull_vertices", [](const Particle& p) { return p.hull_vertices; });
  const char* axis[3] = {"z", "y", "x"};
  for (int a = 0; a < 3; ++a) {
    col(std::string("bbox_") + axis[a] + "0", [a](const Particle& p) { return p.stats.box_lo[a]; });
    col(std::string("bbox_") + axis[a] + "1", [a](const Particle& p) { return p.stats.box_hi[a]; });
  }
  for (int a = 0; a < 3; ++a)
    col("inertia" + std::to_string(a + 1) + "_mm5", [&, a](const Particle& p) { return p.stats.principal_moments_m5[a] * mm5; });
  for (int a = 0; a < 3; ++a)
    col("ell_d" + std::to_string(a + 1) + "_mm", [&, a](const Particle& p) { return 2 * p.stats.ellipsoid_semi_axes_m[a] * mm; });
  // The major axis, sign chosen so that its first non-zero component (z, y, x) is positive.
  auto major = [](const Particle& p) {
    Eigen::Vector3d u = p.stats.ellipsoid_axes.col(0);
    for (int c = 0; c < 3; ++c)
      if (u[c] != 0) return u[c] < 0 ? Eigen::Vector3d(-u) : u;
    return u;
  };
  col("ell_axis1_z", [&](const Particle& p) { return major(p)[0]; });
  col("ell_axis1_y", [&](const Particle& p) { return major(p)[1]; });
  col("ell_axis1_x", [&](const Particle& p) { return major(p)[2]; });
  if (!ps.empty() && ps.front().convex_volume_m3 >= 0) {
    col("convex_volume_mm3", [&](const Particle& p) { return p.convex_volume_m3 * mm3; });
    col("solidity", [](const Particle& p) { return p.solidity; });
  }
  if (!ps.empty() && ps.front().surface_m2 >= 0) {
    col("surface_mm2", [&](const Particle& p) { return p.surface_m2 * 1e6; });
    col("sphericity", [](const Particle& p) { return p.sphericity; });
  }
  if (!ps.empty() && ps.front().coordination >= 0) col("coordination", [](const Particle& p) { return p.coordination; });
  if (!ps.empty() && ps.front().grey_volume_m3 >= 0)
    col("label_volume_mm3", [&](const Particle& p) { return p.stats.volume_m3 * mm3; });
  return t;
}

}  // namespace tg::measure

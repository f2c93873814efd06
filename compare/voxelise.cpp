#include "compare/voxelise.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

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

ClusterBody cluster_body_from_name(const std::string& name) {
  if (name == "hull") return ClusterBody::hull;
  if (name == "members") return ClusterBody::members;
  throw UsageError("cluster body must be hull or members, not '" + name + "'");
}

// The hull of spheres is bounded by patches of the member spheres, of cones
// tangent to two members and of planes tangent to three. A polytope of
// support planes converges to it like ρ θ² only where the normals are spread
// over the patch; on a flat facet or along a cone one direction off the
// exact normal leaves a wedge ∝ θ × the facet's width (measured: +7 % of the
// template's hull volume from 256 lattice directions alone). So the planes
// are (a) the facets' exact normals (tangent to three members, all members on
// one side), (b) normals sampled along every cone's circle of normals where
// both its members support, (c) the lattice for the sphere patches.
synth::Particle hull_body(const synth::Particle& cluster, int directions) {
  if (directions < 4) throw UsageError("voxelise: a hull body needs at least 4 directions");
  std::vector<synth::Sphere> m;
  for (const synth::Piece& pc : cluster.pieces) m.push_back(pc.sphere);
  const size_t n = m.size();
  double scale = 0;
  for (const auto& s : m) scale = std::max(scale, s.r);
  const double tol = 1e-9 * std::max(scale, 1.0);
  auto support = [&](const synth::Vec3& u) {
    double h = std::numeric_limits<double>::lowest();
    for (const auto& s : m) h = std::max(h, synth::dot(u, s.c) + s.r);
    return h;
  };
  std::vector<synth::Vec3> dirs;
  // (c) Fibonacci lattice: near-uniform directions.
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int i = 0; i < directions; ++i) {
    const double z = 1 - (2 * i + 1) / static_cast<double>(directions), rho = std::sqrt(1 - z * z);
    dirs.push_back({z, rho * std::sin(i * golden), rho * std::cos(i * golden)});
  }
  // (b) Cones: the normals u with u·c_a + r_a = u·c_b + r_b form a circle;
  // 32 samples of it, kept where a and b are the support.
  constexpr int kCircle = 32;
  if (n <= 128)
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b) {
        const synth::Vec3 w{m[a].c[0] - m[b].c[0], m[a].c[1] - m[b].c[1], m[a].c[2] - m[b].c[2]};
        const double d = std::sqrt(synth::dot(w, w));
        if (!(d > std::abs(m[a].r - m[b].r))) continue;  // one inside the other: no cone
        const synth::Vec3 e0 = synth::unit(w);
        const synth::Vec3 e1 = synth::unit(synth::cross(e0, std::abs(e0[0]) < 0.9 ? synth::Vec3{1, 0, 0} : synth::Vec3{0, 1, 0}));
        const synth::Vec3 e2 = synth::cross(e0, e1);
        const double ca = (m[b].r - m[a].r) / d, sa = std::sqrt(1 - ca * ca);
        for (int k = 0; k < kCircle; ++k) {
          const double t = 2 * std::numbers::pi * k / kCircle, ct = std::cos(t), st = std::sin(t);
          const synth::Vec3 u{ca * e0[0] + sa * (ct * e1[0] + st * e2[0]), ca * e0[1] + sa * (ct * e1[1] + st * e2[1]),
                              ca * e0[2] + sa * (ct * e1[2] + st * e2[2])};
          if (support(u) <= synth::dot(u, m[a].c) + m[a].r + tol) dirs.push_back(u);
        }
      }
  // (a) Facets: u·(c_a − c_b) = r_b − r_a, u·(c_a − c_c) = r_c − r_a, |u| = 1
  // (two solutions: the particular solution in span(p, q) plus ± t (p × q)).
  if (n <= 32)
    for (size_t a = 0; a < n; ++a)
      for (size_t b = a + 1; b < n; ++b)
        for (size_t c = b + 1; c < n; ++c) {
          const synth::Vec3 p{m[a].c[0] - m[b].c[0], m[a].c[1] - m[b].c[1], m[a].c[2] - m[b].c[2]};
          const synth::Vec3 q{m[a].c[0] - m[c].c[0], m[a].c[1] - m[c].c[1], m[a].c[2] - m[c].c[2]};
          const double bp = m[b].r - m[a].r, bq = m[c].r - m[a].r;
          const synth::Vec3 x = synth::cross(p, q);
          const double pp = synth::dot(p, p), qq = synth::dot(q, q), pq = synth::dot(p, q), det = pp * qq - pq * pq;
          if (!(det > 1e-12 * pp * qq)) continue;  // centres collinear
          const double al = (bp * qq - bq * pq) / det, be = (bq * pp - bp * pq) / det;
          const synth::Vec3 u0{al * p[0] + be * q[0], al * p[1] + be * q[1], al * p[2] + be * q[2]};
          const double rest = 1 - synth::dot(u0, u0);
          if (rest < 0) continue;
          const double t = std::sqrt(rest / synth::dot(x, x));
          for (double sgn : {-1.0, 1.0}) {
            const synth::Vec3 u{u0[0] + sgn * t * x[0], u0[1] + sgn * t * x[1], u0[2] + sgn * t * x[2]};
            if (support(u) <= synth::dot(u, m[a].c) + m[a].r + tol) dirs.push_back(u);
          }
        }
  synth::Particle body;
  body.id = cluster.id;
  body.kind = cluster.kind;
  body.parent = cluster.parent;
  synth::Piece piece;
  // Enclosing sphere: about the mean centre, reaching the farthest member's far side.
  synth::Vec3 mid{0, 0, 0};
  for (const auto& s : m)
    for (int k = 0; k < 3; ++k) mid[k] += s.c[k] / static_cast<double>(n);
  double reach = 0;
  for (const auto& s : m) reach = std::max(reach, std::sqrt(synth::dot({s.c[0] - mid[0], s.c[1] - mid[1], s.c[2] - mid[2]},
                                                                 {s.c[0] - mid[0], s.c[1] - mid[1], s.c[2] - mid[2]})) + s.r);
  piece.sphere = synth::Sphere{mid, reach};
  for (const synth::Vec3& u : dirs) piece.planes.push_back(synth::HalfSpace{u, support(u)});
  body.pieces.push_back(std::move(piece));
  return body;
}

Voxelised voxelise(const SphereTable& s, const VoxeliseOptions& opt) {
  const auto [shape, geom] = voxel_grid(s, opt);
  Voxelised out;
  std::vector<synth::Particle> particles = synth::particles_from_spheres(s, geom, &out.particle_of_label);
  // Clusters imaged as bodies: every later step (render, truth) sees the body.
  const bool hull = opt.cluster_body == ClusterBody::hull;
  if (hull)
    for (synth::Particle& p : particles)
      if (p.kind == synth::Kind::cluster) {
        p = hull_body(p, opt.hull_directions);
        ++out.clusters_hull;
      }
  // What the renderer gets: clusters with disjoint members as separate spheres
  // (render ids 1..n), with label_of[render id] = particle label.
  std::vector<synth::Particle> render_list;
  std::vector<uint32_t> label_of{0};
  bool split_any = false;
  for (const synth::Particle& p : particles) {
    const bool split = p.kind == synth::Kind::cluster && !hull && p.pieces.size() <= 256 &&
                       members_disjoint(p.pieces.data(), p.pieces.data() + p.pieces.size(), opt.member_overlap);
    if (p.kind == synth::Kind::cluster && !hull) ++(split ? out.clusters_split : out.clusters_union);
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
  if (out.clusters_hull > 0) ro.depth = opt.hull_depth;
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
          {"cluster_body", opt.cluster_body == ClusterBody::hull ? "hull" : "members"},
          {"imaging_from", opt.grey ? imaging_from : std::string("no grey scan (labels only)")}};
}

}  // namespace tg::compare

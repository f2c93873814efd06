#include "data_synth/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "core/errors.hpp"
#include "data_synth/partial_volume.hpp"

namespace tg::synth {

namespace {
constexpr const char* kNames[] = {"grain", "half", "multi", "chip", "chipped", "cluster"};
double sphere_volume(double r) { return 4.0 / 3.0 * std::numbers::pi * r * r * r; }
}  // namespace

const char* kind_name(Kind k) { return kNames[static_cast<int>(k)]; }

Kind kind_from_name(const std::string& name) {
  for (int k = 0; k < 6; ++k)
    if (name == kNames[k]) return static_cast<Kind>(k);
  throw InputError("unknown particle kind '" + name + "' (grain, half, multi, chip, chipped, cluster)");
}

Particle make_grain(uint32_t id, Vec3 c, double r) {
  Particle p;
  p.id = id;
  p.parent = id;
  p.kind = Kind::grain;
  p.pieces.push_back(Piece{Sphere{c, r}, {}});
  return p;
}

Particle make_cap(uint32_t id, Kind kind, uint32_t parent, const Sphere& s, Vec3 n, double offset) {
  const double len = std::sqrt(dot(n, n));
  if (!(len > 0)) throw UsageError("make_cap: zero normal");
  for (double& v : n) v /= len;
  Particle p;
  p.id = id;
  p.kind = kind;
  p.parent = parent;
  // n·(p − c) >= offset  <=>  (−n)·p <= −offset − n·c
  p.pieces.push_back(Piece{s, {HalfSpace{{-n[0], -n[1], -n[2]}, -offset - dot(n, s.c)}}});
  return p;
}

Particle make_cluster(uint32_t id, uint32_t parent, std::vector<Sphere> spheres) {
  Particle p;
  p.id = id;
  p.parent = parent;
  p.kind = Kind::cluster;
  for (const Sphere& s : spheres) p.pieces.push_back(Piece{s, {}});
  return p;
}

std::vector<Particle> particles_from_spheres(const SphereTable& s, const Geometry& g,
                                             std::vector<int64_t>* particle_of_label) {
  if (!g.has_voxel_size() || !g.isotropic())
    throw UsageError(s.source + ": mapping spheres to voxels needs an isotropic voxel size");
  const double v = g.voxel_size_m[0];
  std::map<int64_t, size_t> slot;  // particle id -> index in `groups`
  std::vector<std::vector<Sphere>> groups;
  std::vector<int64_t> ids;
  for (size_t q = 0; q < s.size(); ++q) {
    auto [it, fresh] = slot.try_emplace(s.particle[q], groups.size());
    if (fresh) {
      groups.emplace_back();
      ids.push_back(s.particle[q]);
    }
    groups[it->second].push_back(Sphere{{(s.z_m[q] - g.origin_m[0]) / v, (s.y_m[q] - g.origin_m[1]) / v,
                                         (s.x_m[q] - g.origin_m[2]) / v},
                                        s.r_m[q] / v});
  }
  if (groups.size() >= std::numeric_limits<uint32_t>::max()) throw InputError(s.source + ": too many particles");
  std::vector<Particle> out;
  out.reserve(groups.size());
  for (size_t n = 0; n < groups.size(); ++n) {
    const auto id = static_cast<uint32_t>(n + 1);
    out.push_back(groups[n].size() == 1 ? make_grain(id, groups[n][0].c, groups[n][0].r)
                                        : make_cluster(id, id, std::move(groups[n])));
  }
  if (particle_of_label) {
    particle_of_label->assign(1, -1);
    particle_of_label->insert(particle_of_label->end(), ids.begin(), ids.end());
  }
  return out;
}

void bounding_box(const Particle& p, Vec3& lo, Vec3& hi) {
  lo = {1e300, 1e300, 1e300};
  hi = {-1e300, -1e300, -1e300};
  for (const Piece& pc : p.pieces)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], pc.sphere.c[a] - pc.sphere.r);
      hi[a] = std::max(hi[a], pc.sphere.c[a] + pc.sphere.r);
    }
}

double cap_volume(double R, double h) { return std::numbers::pi * h * h * (3 * R - h) / 3; }
double cap_centroid_offset(double R, double h) { return 3 * (2 * R - h) * (2 * R - h) / (4 * (3 * R - h)); }

Truth particle_truth(const Particle& p) {
  Truth t;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (p.pieces.empty()) throw UsageError("particle " + std::to_string(p.id) + " has no pieces");
  for (const Piece& pc : p.pieces) t.radius = std::max(t.radius, pc.sphere.r);
  const Piece& first = p.pieces.front();
  const double R = first.sphere.r;
  const bool grain = p.pieces.size() == 1 && first.planes.empty();
  const bool cap = p.pieces.size() == 1 && first.planes.size() == 1;
  if (grain || cap) {
    double V, h = 2 * R;
    Vec3 c = first.sphere.c;
    if (grain) {
      V = sphere_volume(R);
      t.dmax = t.dmin = 2 * R;
    } else {
      const HalfSpace& hs = first.planes.front();
      h = std::clamp(R + (hs.d - dot(hs.n, c)), 0.0, 2 * R);
      V = cap_volume(R, h);
      const double off = cap_centroid_offset(R, h);
      for (int a = 0; a < 3; ++a) c[a] -= hs.n[a] * off;
      t.dmax = h <= R ? 2 * std::sqrt(h * (2 * R - h)) : 2 * R;
      t.dmin = std::min(h, t.dmax);
    }
    // Dmed (and FR) use the pore-free volume: the pipeline fills intra-granular
    // pores before measuring, and a porous sphere is still FR = AR = 1.
    t.dmed = (t.dmax > 0 && t.dmin > 0) ? 6 * V / (std::numbers::pi * t.dmax * t.dmin) : 0;
    Vec3 m{V * c[0], V * c[1], V * c[2]};
    for (const Sphere& s : p.pores) {
      const double vp = sphere_volume(s.r);
      V -= vp;
      for (int a = 0; a < 3; ++a) m[a] -= vp * s.c[a];
    }
    t.volume = V;
    for (int a = 0; a < 3; ++a) t.centroid[a] = V > 0 ? m[a] / V : c[a];
    t.fr = t.dmed > 0 ? t.dmin / t.dmed : nan;
    t.ar = t.dmin > 0 ? t.dmax / t.dmin : nan;
    return t;
  }
  // Wedges and clusters: volume from the partial-volume rules on 8³ cells of the
  // bounding box, 4 levels of subdivision (exact except near plane/sphere or
  // sphere/sphere intersection curves); centroid from a chord quadrature.
  Vec3 lo, hi, m;
  bounding_box(p, lo, hi);
  constexpr int cells = 8;
  const CoverageOptions opt{8, 4};
  double V = 0;
  for (int a = 0; a < cells; ++a)
    for (int b = 0; b < cells; ++b)
      for (int c = 0; c < cells; ++c) {
        Vec3 l, h;
        const int idx[3] = {a, b, c};
        for (int d = 0; d < 3; ++d) {
          l[d] = lo[d] + (hi[d] - lo[d]) * idx[d] / cells;
          h[d] = lo[d] + (hi[d] - lo[d]) * (idx[d] + 1) / cells;
        }
        V += box_coverage(p, l, h, opt);
      }
  t.volume = V;
  const double vq = chord_volume(p, lo, hi, 32, 8, &m);
  for (int a = 0; a < 3; ++a) t.centroid[a] = vq > 0 ? m[a] / vq : 0.5 * (lo[a] + hi[a]);
  t.dmax = t.dmin = t.dmed = t.fr = t.ar = nan;
  return t;
}

}  // namespace tg::synth

#include "data_synth/granule.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "data_synth/rng.hpp"

namespace tg::synth {

namespace {

bool pore_inside(const Sphere& pore, const Piece& pc) {
  for (const HalfSpace& h : pc.planes)
    if (dot(h.n, pore.c) + pore.r > h.d) return false;
  return true;
}
// Stream keys: one per grain and purpose.
constexpr uint64_t kBreak = 0xb4ea0000, kPores = 0x90e50000;

}  // namespace

void add_pores(Particle& g, int count, double radius_frac, uint64_t seed) {
  if (g.pieces.size() != 1 || !g.pieces[0].planes.empty()) throw UsageError("add_pores: intact grains only");
  if (count <= 0) return;
  if (!(radius_frac > 0 && radius_frac < 0.45)) throw InputError("pore radius fraction must be in (0, 0.45)");
  const Sphere& s = g.pieces[0].sphere;
  const double rp = radius_frac * s.r, reach = s.r - rp - 0.05 * s.r;
  Stream rng(seed, kPores + g.id);
  for (int tries = 0; tries < 100 * count && static_cast<int>(g.pores.size()) < count; ++tries) {
    Vec3 p{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    if (dot(p, p) > 1) continue;
    for (int a = 0; a < 3; ++a) p[a] = s.c[a] + reach * p[a];
    bool ok = true;
    for (const Sphere& q : g.pores) {
      const Vec3 d{p[0] - q.c[0], p[1] - q.c[1], p[2] - q.c[2]};
      if (dot(d, d) < (2 * rp + 0.05 * s.r) * (2 * rp + 0.05 * s.r)) ok = false;
    }
    if (ok) g.pores.push_back(Sphere{p, rp});
  }
}

Event draw_event(uint32_t id, const BreakageOptions& o) {
  const double total = o.mix_split + o.mix_multi + o.mix_chip;
  if (!(total > 0) || o.mix_split < 0 || o.mix_multi < 0 || o.mix_chip < 0)
    throw InputError("breakage mix must be non-negative with a positive sum");
  const double u = uniform01(o.seed, kBreak + id, 1) * total;
  if (u < o.mix_split) return Event::split;
  if (u < o.mix_split + o.mix_multi) return Event::multi;
  return Event::chip;
}

std::vector<Particle> fragment(const Particle& g, Event e, uint32_t first, const BreakageOptions& o) {
  if (g.pieces.size() != 1 || !g.pieces[0].planes.empty()) throw UsageError("fragment: intact grains only");
  const Sphere& s = g.pieces[0].sphere;
  const double half_gap = 0.5 * o.gap;
  if (!(o.gap >= 0 && half_gap < 0.5 * s.r))
    throw InputError("fragment gap " + std::to_string(o.gap) + " too wide for a grain of radius " + std::to_string(s.r));
  const uint64_t key = kBreak + g.id;
  const Vec3 n = random_direction(o.seed, key, 10);
  std::vector<Particle> out;
  auto piece = [&](Kind kind, std::vector<HalfSpace> planes) {
    Particle p;
    p.id = first + static_cast<uint32_t>(out.size());
    p.kind = kind;
    p.parent = g.id;
    p.pieces.push_back(Piece{s, std::move(planes)});
    for (const Sphere& pore : g.pores)
      if (pore_inside(pore, p.pieces[0])) p.pores.push_back(pore);
    out.push_back(std::move(p));
  };
  switch (e) {
    case Event::none:
      out.push_back(g);
      break;
    case Event::split:
      piece(Kind::half, {keep_above(n, s.c, half_gap)});
      piece(Kind::half, {keep_above({-n[0], -n[1], -n[2]}, s.c, half_gap)});
      break;
    case Event::multi: {
      // m wedges around axis n, boundaries at angles φ0 + 2πk/m in the plane ⟂ n.
      const int m = uniform01(o.seed, key, 20) < 0.5 ? 3 : 4;
      const Vec3 t = std::abs(n[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
      const Vec3 e1 = unit(cross(n, t)), e2 = cross(n, e1);
      const double phi0 = 2 * std::numbers::pi * uniform01(o.seed, key, 21);
      auto normal_at = [&](double phi) {  // in-plane unit normal of the half-plane at angle φ, towards +φ
        return Vec3{-std::sin(phi) * e1[0] + std::cos(phi) * e2[0], -std::sin(phi) * e1[1] + std::cos(phi) * e2[1],
                    -std::sin(phi) * e1[2] + std::cos(phi) * e2[2]};
      };
      for (int k = 0; k < m; ++k) {
        const double a = phi0 + 2 * std::numbers::pi * k / m, b = phi0 + 2 * std::numbers::pi * (k + 1) / m;
        const Vec3 na = normal_at(a), nb = normal_at(b);
        piece(Kind::multi, {keep_above(na, s.c, half_gap), keep_above({-nb[0], -nb[1], -nb[2]}, s.c, half_gap)});
      }
      break;
    }
    case Event::chip: {
      const double t = s.r * (o.chip_min + (o.chip_max - o.chip_min) * uniform01(o.seed, key, 30));
      piece(Kind::chipped, {keep_above({-n[0], -n[1], -n[2]}, s.c, -(s.r - t) + half_gap)});
      piece(Kind::chip, {keep_above(n, s.c, s.r - t + half_gap)});
      break;
    }
  }
  return out;
}

std::vector<Particle> stage_particles(const std::vector<Particle>& grains, double z_bottom, int stage,
                                      const StageOptions& o) {
  if (o.strains.empty() || o.strains.size() != o.broken.size())
    throw InputError("stages: strains and broken fractions must be lists of the same length");
  if (stage < 0 || stage >= static_cast<int>(o.strains.size())) throw UsageError("stage index out of range");
  const double emax = *std::max_element(o.strains.begin(), o.strains.end());
  for (size_t q = 0; q < o.strains.size(); ++q)
    if (!(o.strains[q] >= 0 && o.strains[q] < 1) || !(o.broken[q] >= 0 && o.broken[q] <= 1))
      throw InputError("stages: strains must be in [0, 1), broken fractions in [0, 1]");
  const double f = (1 - o.strains[stage]) / (1 - emax);
  uint32_t max_id = 0;
  for (const Particle& g : grains) max_id = std::max(max_id, g.id);
  const uint32_t first_fragment = max_id + 1;
  std::vector<Particle> out;
  for (const Particle& g0 : grains) {
    Particle g = g0;
    const double dz = (z_bottom + (g.pieces[0].sphere.c[0] - z_bottom) * f) - g.pieces[0].sphere.c[0];
    for (Piece& pc : g.pieces) pc.sphere.c[0] += dz;
    for (Sphere& p : g.pores) p.c[0] += dz;
    const bool broken = uniform01(o.breakage.seed, kBreak + g.id, 0) < o.broken[stage];
    if (!broken) {
      out.push_back(std::move(g));
      continue;
    }
    for (Particle& p : fragment(g, draw_event(g.id, o.breakage), first_fragment + 4 * (g.id - 1), o.breakage))
      out.push_back(std::move(p));
  }
  return out;
}

}  // namespace tg::synth

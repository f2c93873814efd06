// Scenes of spheres with exactly known contacts, for the contact tests and
// benchmarks (tests/measure/contacts_test.cpp, bench/measure/contacts_bench.cpp).
//
// grow_scene: spheres of radius scale * [20, 23] voxels grown one by one,
// each overlapping one or two earlier spheres by `overlap` (a contact, as
// between DEM spheres) along their line of centres and at least `margin`
// from every other sphere (not a contact). Single-contact directions are
// stretched along z (x2 before normalising), so the fabric is anisotropic.
// cut_lines: a one-voxel 26-separating line between touching labels (the
// larger label gives up its voxels that have a smaller one among their 26
// neighbours), as a watershed with lines would leave.
#pragma once
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/volume.hpp"
#include "data_synth/geometry.hpp"
#include "data_synth/render.hpp"

namespace tg::measure::test {

using Eigen::Vector3d;

struct Scene {
  std::vector<Eigen::Vector3d> c;
  std::vector<double> r;
  std::vector<std::pair<int, int>> contacts;  // indices, first < second
};

// See the file's header. Directions of single contacts are stretched along z
// (factor 2 before normalising), so the fabric is anisotropic.
// scale: grain radii are scale * [20, 23] voxels (scale 1 = the test's);
// overlap and margin are in voxels at scale 1 and scale with the grains, so
// one seed gives the same physical scene at every voxel size.
inline Scene grow_scene(int64_t n, unsigned seed, int target, double overlap = 0.6, double margin = 3.0, double scale = 1.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> G;
  Scene s;
  s.c.push_back(Eigen::Vector3d::Constant(n / 2.0) + Eigen::Vector3d(U(rng), U(rng), U(rng)));
  s.r.push_back(21.0 * scale);
  const double lo = 8 * scale, hi = static_cast<double>(n) - 8 * scale;
  overlap *= scale;
  margin *= scale;
  for (int attempt = 0; attempt < 20000 && static_cast<int>(s.c.size()) < target; ++attempt) {
    const double r = scale * (20 + 3 * U(rng));
    const int P = static_cast<int>(U(rng) * static_cast<double>(s.c.size()));
    std::vector<int> touch{P};
    Eigen::Vector3d c;
    if (attempt % 2 == 0) {
      Eigen::Vector3d u(2 * G(rng), G(rng), G(rng));
      c = s.c[P] + (s.r[P] + r - overlap) * u.normalized();
    } else {
      // Tangent (less the overlap) to P and to a neighbour Q of P: a point on
      // the circle where the two spheres of reach intersect.
      std::vector<int> qs;
      for (int q = 0; q < static_cast<int>(s.c.size()); ++q)
        if (q != P && (s.c[q] - s.c[P]).norm() < s.r[P] + s.r[q] + 2 * r - 2 * overlap - 1) qs.push_back(q);
      if (qs.empty()) continue;
      const int Q = qs[static_cast<size_t>(U(rng) * static_cast<double>(qs.size()))];
      const double dp = s.r[P] + r - overlap, dq = s.r[Q] + r - overlap;
      const Eigen::Vector3d e = s.c[Q] - s.c[P];
      const double L = e.norm();
      const double x = (L * L + dp * dp - dq * dq) / (2 * L);
      const double rr = dp * dp - x * x;
      if (rr <= 0) continue;
      const Eigen::Vector3d ez = e / L;
      Eigen::Vector3d e1 = ez.unitOrthogonal(), e2 = ez.cross(e1);
      const double t = 2 * std::numbers::pi * U(rng);
      c = s.c[P] + x * ez + std::sqrt(rr) * (std::cos(t) * e1 + std::sin(t) * e2);
      touch.push_back(Q);
    }
    if ((c.array() < lo).any() || (c.array() > hi).any()) continue;
    bool ok = true;
    for (int q = 0; q < static_cast<int>(s.c.size()) && ok; ++q) {
      if (std::find(touch.begin(), touch.end(), q) != touch.end()) continue;
      ok = (c - s.c[q]).norm() - r - s.r[q] >= margin;
    }
    if (!ok) continue;
    const int id = static_cast<int>(s.c.size());
    s.c.push_back(c);
    s.r.push_back(r);
    for (int q : touch) s.contacts.push_back({q, id});
  }
  return s;
}

inline Volume<uint32_t> render_scene(const Scene& s, int64_t n, double voxel_m) {
  std::vector<synth::Particle> ps;
  for (size_t p = 0; p < s.c.size(); ++p)
    ps.push_back(synth::make_grain(static_cast<uint32_t>(p + 1), {s.c[p][0], s.c[p][1], s.c[p][2]}, s.r[p]));
  auto r = synth::render(ps, Shape{n, n, n}, Geometry::isotropic_m(voxel_m));
  return std::move(r.labels);
}

// A one-voxel 26-separating line between touching labels: a voxel gives way
// when a smaller non-zero label is among its 26 neighbours (in the input).
// Angle between two directions, degrees.
inline double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / std::numbers::pi;
}

inline Volume<uint32_t> cut_lines(const Volume<uint32_t>& in) {
  Volume<uint32_t> out = in.clone();
  const Shape s = in.shape();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        const uint32_t l = in(k, j, i);
        if (!l) continue;
        bool cut = false;
        for (int64_t dk = -1; dk <= 1 && !cut; ++dk)
          for (int64_t dj = -1; dj <= 1 && !cut; ++dj)
            for (int64_t di = -1; di <= 1 && !cut; ++di) {
              const int64_t a = k + dk, b = j + dj, c = i + di;
              if (a < 0 || b < 0 || c < 0 || a >= s.nz || b >= s.ny || c >= s.nx) continue;
              const uint32_t m = in(a, b, c);
              cut = m != 0 && m < l;
            }
        if (cut) out(k, j, i) = 0;
      }
  return out;
}

}  // namespace tg::measure::test

#include "dem/breakage/fragment_template.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tg::dem::breakage {
namespace {

FragmentTemplate build() {
  constexpr double pi = std::numbers::pi;
  FragmentTemplate t;
  // Ring A: positive root of ra² + 2 s ra − s = 0, s = sin²(π/8).
  const double s = std::sin(pi / 8) * std::sin(pi / 8);
  t.ra = -s + std::sqrt(s * s + s);
  const double rho_a = std::sqrt(1 - 2 * t.ra);  // horizontal distance of A centres
  // Central sphere at (0,0,rc): ρa² + (ra − rc)² = (ra + rc)²  →  rc = ρa² / (4 ra).
  t.rc = rho_a * rho_a / (4 * t.ra);
  // Ring B: for a trial rb, the polar angle θ follows from tangency with the
  // centre sphere (law of cosines); bisect on the gap to the A neighbour.
  auto b_centre = [&](double rb) {
    const double d = 1 - rb;
    const double ct = (d * d + t.rc * t.rc - (t.rc + rb) * (t.rc + rb)) / (2 * d * t.rc);
    const double st = std::sqrt(std::max(0.0, 1 - ct * ct));
    return Vec3{d * st * std::cos(pi / 8), d * st * std::sin(pi / 8), d * ct};
  };
  const Vec3 a0{rho_a, 0, t.ra};
  auto gap = [&](double rb) { return norm(b_centre(rb) - a0) - (t.ra + rb); };
  double lo = 0.1, hi = 0.25;  // gap(lo) > 0 > gap(hi) (checked by the tests via tangency)
  for (int it = 0; it < 200 && hi - lo > 1e-16; ++it) {
    const double mid = 0.5 * (lo + hi);
    (gap(mid) > 0 ? lo : hi) = mid;
  }
  t.rb = 0.5 * (lo + hi);
  const Vec3 b0 = b_centre(t.rb);
  const double rho_b = std::hypot(b0.x, b0.y);

  t.spheres[0] = {{0, 0, t.rc}, t.rc};
  for (int k = 0; k < 8; ++k) {
    const double a = k * pi / 4, b = pi / 8 + k * pi / 4;
    t.spheres[1 + k] = {{rho_a * std::cos(a), rho_a * std::sin(a), t.ra}, t.ra};
    t.spheres[9 + k] = {{rho_b * std::cos(b), rho_b * std::sin(b), b0.z}, t.rb};
  }
  // Bonds: centre–A, centre–B, A–A neighbours, B–its two A neighbours.
  for (int k = 0; k < 8; ++k) {
    t.bonds.push_back({0, 1 + k});
    t.bonds.push_back({0, 9 + k});
    const int a_next = 1 + (k + 1) % 8;
    t.bonds.push_back({std::min(1 + k, a_next), std::max(1 + k, a_next)});
    t.bonds.push_back({1 + k, 9 + k});       // B_k sits between A_k and A_{k+1}
    t.bonds.push_back({a_next, 9 + k});
  }
  for (auto& b : t.bonds)
    if (b[0] > b[1]) std::swap(b[0], b[1]);
  return t;
}

}  // namespace

double FragmentTemplate::retained_fraction() const {
  double s = 0;
  for (const auto& sp : spheres) s += sp.r * sp.r * sp.r;
  return 2 * s;  // two fragments, spheres disjoint, mother volume ∝ 1³
}

Vec3 FragmentTemplate::centroid() const {
  Vec3 c{};
  double m = 0;
  for (const auto& sp : spheres) {
    const double w = sp.r * sp.r * sp.r;
    c = c + w * sp.c;
    m += w;
  }
  return (1 / m) * c;
}

const FragmentTemplate& fragment_template() {
  static const FragmentTemplate t = build();
  return t;
}

}  // namespace tg::dem::breakage

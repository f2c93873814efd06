#include "dem/breakage/replacement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "dem/breakage/fragment_template.hpp"

using namespace tg::dem;
using namespace tg::dem::breakage;

namespace {
const Mother kMother{{1e-3, 2e-3, 3e-3}, 6e-4, {0.1, -0.2, 0.05}, {30, 10, -20}};
Vec3 unit(Vec3 v) { return (1 / norm(v)) * v; }
const Vec3 kNormal = unit({1, 2, -0.5});
const Vec3 kNf = unit(cross(kNormal, {0, 0, 1}));
}  // namespace

TEST(Replacement, FragmentsInsideMotherOnTheirSideOfThePlane) {
  const Replacement rep = replace_sphere(kMother, kNormal, kNf);
  for (const auto& s : rep.spheres) {
    EXPECT_LE(norm(s.x - kMother.x) + s.r, kMother.r * (1 + 1e-12)) << s.slot;
    const double h = dot(s.x - kMother.x, kNormal);  // signed distance to the plane
    const double side = s.fragment == 0 ? 1.0 : -1.0;
    EXPECT_GE(side * h - s.r, -1e-12 * kMother.r) << s.slot;
  }
  // The template's A sphere at azimuth 0 faces the maximum-force contact.
  EXPECT_GT(dot(unit(rep.spheres[1].x - kMother.x), kNf), 0.9);
}

TEST(Replacement, BondsStayInsideEachFragmentAndAreTangent) {
  const Replacement rep = replace_sphere(kMother, kNormal, kNf);
  ASSERT_EQ(rep.bonds.size(), 80u);
  for (auto b : rep.bonds) {
    const auto &p = rep.spheres[b[0]], &q = rep.spheres[b[1]];
    EXPECT_EQ(p.fragment, q.fragment);
    EXPECT_NEAR(norm(p.x - q.x), p.r + q.r, 1e-12 * kMother.r);
  }
}

TEST(Replacement, VolumeLostIsTheTemplateFraction) {
  const Replacement rep = replace_sphere(kMother, kNormal, kNf);
  const double v = 4.0 / 3.0 * std::numbers::pi * std::pow(kMother.r, 3);
  EXPECT_NEAR(rep.volume_mother, v, 1e-15 * v);
  EXPECT_NEAR(rep.volume_retained / v, fragment_template().retained_fraction(), 1e-12);
  EXPECT_NEAR(rep.volume_lost / v, 0.4596, 1e-4);
}

// Rigid-body field: momentum of the fragments = retained mass × v (their mass
// centre is the mother's centre), and no bonded pair has a relative normal
// velocity, so bonds are born unloaded.
TEST(Replacement, InheritsRigidBodyMotion) {
  const Replacement rep = replace_sphere(kMother, kNormal, kNf);
  Vec3 p{}, xm{};
  double m = 0;
  for (const auto& s : rep.spheres) {
    const double ms = s.r * s.r * s.r;
    p = p + ms * s.v;
    xm = xm + ms * s.x;
    m += ms;
    EXPECT_EQ(s.w.x, kMother.w.x);
  }
  EXPECT_NEAR(norm((1 / m) * p - kMother.v), 0, 1e-12);
  EXPECT_NEAR(norm((1 / m) * xm - kMother.x), 0, 1e-15);
  for (auto b : rep.bonds) {
    const auto &a = rep.spheres[b[0]], &c = rep.spheres[b[1]];
    EXPECT_NEAR(dot(c.v - a.v, unit(c.x - a.x)), 0, 1e-12);
  }
}

// Random neighbours overlapping the mother by up to 5 % of its radius, and a
// wall plane touching it: no fragment sphere overlaps any of them more than
// the mother did.
TEST(Replacement, CreatesNoNewOverlap) {
  std::mt19937_64 gen(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 n = unit({u(gen), u(gen), u(gen)});
    const Vec3 nf = unit(cross(n, unit({u(gen), u(gen), u(gen)})));
    const Replacement rep = replace_sphere(kMother, n, nf);
    for (int j = 0; j < 12; ++j) {
      const Vec3 dir = unit({u(gen), u(gen), u(gen)});
      const double rn = kMother.r * (0.3 + 0.7 * std::abs(u(gen)));
      const double mother_overlap = 0.05 * kMother.r * std::abs(u(gen));
      const Vec3 xn = kMother.x + (kMother.r + rn - mother_overlap) * dir;
      for (const auto& s : rep.spheres) {
        const double ov = s.r + rn - norm(s.x - xn);
        EXPECT_LE(ov, mother_overlap + 1e-12 * kMother.r);
      }
      // Wall with outward normal dir, penetrating the mother by mother_overlap.
      const double wall = dot(kMother.x, dir) + kMother.r - mother_overlap;
      for (const auto& s : rep.spheres) EXPECT_LE(dot(s.x, dir) + s.r - wall, mother_overlap + 1e-12 * kMother.r);
    }
  }
}

// The DEM particles' shapes straight from their spheres
// (compare/dem_stage.hpp exact_shape_sample), against hand-computed hulls:
// a lone sphere, two and three tangent equal spheres in a row (capsules),
// and the DEM's own 17-sphere fragment, turned at random.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include <omp.h>

#include <Eigen/Geometry>

#include "compare/dem_stage.hpp"
#include "dem/breakage/fragment_template.hpp"

namespace tg {
namespace {

constexpr double kShapeR = 0.3e-3;  // 0.3 mm
constexpr double kShapePi = std::numbers::pi;

// Particle 1: a lone sphere; 2: two tangent spheres along x; 3: three along a tilted axis.
SphereTable shape_particles() {
  SphereTable s;
  s.push_back(0, 0, 0, kShapeR, 1);
  for (int q = 0; q < 2; ++q) s.push_back(5e-3 + 2 * q * kShapeR, 0, 0, kShapeR, 2);
  const double ux = 0.6, uy = 0.0, uz = 0.8;
  for (int q = 0; q < 3; ++q) s.push_back(-5e-3 + 2 * q * kShapeR * ux, 2e-3 + 2 * q * kShapeR * uy, 1e-3 + 2 * q * kShapeR * uz, kShapeR, 3);
  return s;
}

TEST(ExactShapes, SphereAndCapsulesMatchTheirHulls) {
  const measure::GradingSample g = compare::exact_shape_sample(shape_particles());
  ASSERT_EQ(g.fr.size(), 3u);
  const double r = kShapeR * 1e3;  // mm
  // A sphere: every caliper is its diameter; Dmed = d; FR = AR = 1.
  EXPECT_DOUBLE_EQ(g.fr[0], 1.0);
  EXPECT_DOUBLE_EQ(g.ar[0], 1.0);
  EXPECT_NEAR(g.size_mm[0], 2 * r, 1e-12);
  EXPECT_NEAR(g.mass[0], 4.0 / 3.0 * kShapePi * r * r * r, 1e-12);
  // n tangent spheres in a row: hull = cylinder of length 2 r (n - 1) + one sphere, Dmax = 2 r n,
  // Dmin = 2 r, Dmed = 6 V / (pi Dmax Dmin). n = 2: V = 10/3 pi r^3, Dmed 2.5 r, FR 0.8, AR 2;
  // n = 3: V = 16/3 pi r^3, Dmed 8/3 r, FR 0.75, AR 3. The sampled sphere surfaces read the
  // calipers within -0.1 % .. +0.6 % of r: measured +0.2-0.3 % on V, +0.004 on FR.
  for (int n : {2, 3}) {
    const size_t q = static_cast<size_t>(n - 1);
    const double v = (2.0 * (n - 1) + 4.0 / 3.0) * kShapePi * r * r * r;
    EXPECT_NEAR(g.mass[q], v, 0.005 * v) << n;
    EXPECT_NEAR(g.ar[q], n, 0.01 * n) << n;
    EXPECT_NEAR(g.fr[q], 2.0 / (6.0 * (2.0 * (n - 1) + 4.0 / 3.0) / (4.0 * n)), 0.006) << n;
    EXPECT_NEAR(g.deq_mm[q], 2 * r * std::cbrt(n), 1e-9) << n;
  }
}

// The spheres' order in the table does not change the result (particles come out by id).
TEST(ExactShapes, SphereOrderDoesNotMatter) {
  const SphereTable a = shape_particles();
  SphereTable b;
  for (size_t q = a.size(); q-- > 0;) b.push_back(a.x_m[q], a.y_m[q], a.z_m[q], a.r_m[q], a.particle[q]);
  const measure::GradingSample ga = compare::exact_shape_sample(a), gb = compare::exact_shape_sample(b);
  for (size_t q = 0; q < 3; ++q) {
    EXPECT_NEAR(ga.fr[q], gb.fr[q], 1e-9);
    EXPECT_NEAR(ga.ar[q], gb.ar[q], 1e-9);
    EXPECT_NEAR(ga.mass[q], gb.mass[q], 1e-9 * ga.mass[q]);
  }
}

// The DEM's fragment template (dem/breakage/fragment_template.hpp; mother radius 0.7 mm) as 24
// particles turned at random: AR is its Dmax / Dmin from the template's radii, 2 (rho_A + r_A) /
// 2 r_c = 2.116 (dem/breakage/README.md), whatever the turn; FR the same for every turn; and one
// thread or two give the same numbers.
TEST(ExactShapes, FragmentTemplateAtAnyTurn) {
  const auto& t = dem::breakage::fragment_template();
  const double R = 0.7e-3;
  SphereTable s;
  std::srand(7);
  for (int64_t id = 1; id <= 24; ++id) {
    const Eigen::Quaterniond q = Eigen::Quaterniond::UnitRandom();
    const Eigen::Vector3d at(0.01 * double(id), 0.002 * double(id % 3), -0.003 * double(id % 5));
    for (const auto& sp : t.spheres) {
      const Eigen::Vector3d c = at + R * (q * Eigen::Vector3d(sp.c.x, sp.c.y, sp.c.z));
      s.push_back(c[0], c[1], c[2], R * sp.r, id);
    }
  }
  const double ar = 2 * (std::sqrt(1 - 2 * t.ra) + t.ra) / (2 * t.rc);
  ASSERT_NEAR(ar, 2.116, 1e-3);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const measure::GradingSample one = compare::exact_shape_sample(s);
  omp_set_num_threads(2);
  const measure::GradingSample two = compare::exact_shape_sample(s);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.fr.size(), 24u);
  for (size_t k = 0; k < 24; ++k) {
    EXPECT_NEAR(one.ar[k], ar, 0.01 * ar) << k;
    EXPECT_NEAR(one.fr[k], one.fr[0], 0.01) << k;
    EXPECT_LT(one.fr[k], 0.8);  // a fragment never reads as quasi-spherical
    EXPECT_EQ(one.fr[k], two.fr[k]);
    EXPECT_EQ(one.ar[k], two.ar[k]);
    EXPECT_EQ(one.mass[k], two.mass[k]);
  }
}

}  // namespace
}  // namespace tg

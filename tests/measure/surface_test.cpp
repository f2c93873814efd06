// Surface area and Wadell sphericity (measure/surface.hpp) against analytic
// spheres and boxes drawn by voxel-centre inclusion (random sub-voxel
// centres). The ball radius was chosen on seeds 4-5 (surface.hpp); seeds 6-9
// are held out.
#include "measure/surface.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "measure/label_stats.hpp"
#include "tests/measure/shapes.hpp"

namespace tg::measure {
namespace {

using test::V3;

struct Measured {
  double area_vox2, volume_vox3;
};
Measured measure_one(const Volume<uint32_t>& v) {
  const auto r = label_stats(v.view());
  SurfaceOptions o;
  if (std::getenv("TG_RS")) o.normal_radius_voxels = std::atof(std::getenv("TG_RS"));
  return {surface_area(v.view(), r.labels[0].label, r.surface_of(0), o) / 1e-10, static_cast<double>(r.labels[0].voxels)};
}

// Spheres: within 1 % at radius >= 20 (the bar; +0.15 % at most
// measured), sphericity >= 0.98.
TEST(Surface, SphereAreaWithinOnePercentAtRadius20) {
  for (double R : {20.0, 30.0})
    for (unsigned seed = 4; seed <= 9; ++seed) {
      const auto v = test::draw_one(R, [R](V3 c) { return test::sphere(c, R); }, seed);
      const Measured m = measure_one(v);
      const double truth = 4 * std::numbers::pi * R * R;
      if (std::getenv("TG_DEBUG")) std::printf("R %g seed %u area err %+.4f %%\n", R, seed, 100 * (m.area_vox2 / truth - 1));
      EXPECT_NEAR(m.area_vox2 / truth, 1.0, 0.01) << R << " " << seed;
      const double psi = wadell_sphericity(m.volume_vox3, m.area_vox2);
      if (std::getenv("TG_DEBUG")) std::printf("R %g seed %u sphericity %.4f\n", R, seed, psi);
      EXPECT_GE(psi, 0.98);
      EXPECT_LE(psi, 1.02);
    }
}

// A rotated box 30 x 20 x 12 voxels: flat faces, sharp edges (area 2 (600 +
// 360 + 240) = 2400); the ball's normal is wrong along edges: -4.3 to -4.6 %
// measured (seeds 4-6), asserted within [-6 %, +1 %].
TEST(Surface, RotatedBoxArea) {
  const V3 e(30, 20, 12);
  const double truth = 2 * (e[0] * e[1] + e[0] * e[2] + e[1] * e[2]);
  for (unsigned seed = 4; seed <= 6; ++seed) {
    const auto v = test::draw_one(19, [&](V3 c) { return test::box(c, e, test::random_rotation(seed)); }, seed);
    const Measured m = measure_one(v);
    if (std::getenv("TG_DEBUG")) std::printf("box seed %u area err %+.4f %%\n", seed, 100 * (m.area_vox2 / truth - 1));
    EXPECT_GE(m.area_vox2 / truth, 0.94) << seed;
    EXPECT_LE(m.area_vox2 / truth, 1.01) << seed;
  }
}

// Axis-aligned faces: every weight is <= 1, and faces farther than the ball
// from an edge are exact, so a 40 x 30 x 24 block (area 5760) reads a little
// less than the truth, the loss confined to the band along its 12 edges.
TEST(Surface, AxisAlignedBlock) {
  auto v = Volume<uint32_t>::filled(Shape{28, 34, 44}, 0, Geometry::isotropic_m(1e-5));
  for (int64_t k = 2; k < 26; ++k)
    for (int64_t j = 2; j < 32; ++j)
      for (int64_t i = 2; i < 42; ++i) v(k, j, i) = 3;
  const Measured m = measure_one(v);
  if (std::getenv("TG_DEBUG")) std::printf("block area err %+.4f %%\n", 100 * (m.area_vox2 / 5760 - 1));
  EXPECT_LE(m.area_vox2, 5760.0 + 1e-9);
  EXPECT_GE(m.area_vox2, 5760.0 * 0.95);
}

TEST(Surface, SphericityRules) {
  EXPECT_TRUE(std::isnan(wadell_sphericity(1, 0)));
  const double R = 2.0;
  EXPECT_NEAR(wadell_sphericity(4.0 / 3 * std::numbers::pi * R * R * R, 4 * std::numbers::pi * R * R), 1.0, 1e-12);
}

// One voxel: 6 faces, each with a normal exactly along its axis: area 6.
TEST(Surface, OneVoxel) {
  auto v = Volume<uint32_t>::filled(Shape{3, 3, 3}, 0, Geometry::isotropic_m(1e-5));
  v(1, 1, 1) = 1;
  EXPECT_NEAR(measure_one(v).area_vox2, 6.0, 1e-9);
}

}  // namespace
}  // namespace tg::measure

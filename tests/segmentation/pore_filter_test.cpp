#include "segmentation/pore_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "fixtures.hpp"

namespace tg {
namespace {

using test::draw_ball;

TEST(PoreFilter, SphericityOfDigitalShapes) {
  // Digital ball radius 20: sphericity close to 1 after the 2/3 face correction.
  auto m = Volume<uint8_t>::filled(Shape{45, 45, 45}, 0);
  draw_ball(m, 22, 22, 22, 20);
  int64_t v = 0, f = 0;
  for (int64_t k = 1; k < 44; ++k)
    for (int64_t j = 1; j < 44; ++j)
      for (int64_t i = 1; i < 44; ++i) {
        if (!m(k, j, i)) continue;
        ++v;
        f += !m(k - 1, j, i) + !m(k + 1, j, i) + !m(k, j - 1, i) + !m(k, j + 1, i) + !m(k, j, i - 1) + !m(k, j, i + 1);
      }
  EXPECT_GT(voxel_sphericity(v, f), 0.9);
  // Flat 1-voxel disc of radius 20: V = pi r^2, F ~ 2 V -> Psi ~ 15/r^2.
  const int64_t dv = std::llround(std::numbers::pi * 400);
  EXPECT_LT(voxel_sphericity(dv, 2 * dv + 126), 0.05);
  EXPECT_EQ(voxel_sphericity(1, 6), 1.0);  // clipped
  EXPECT_EQ(voxel_sphericity(0, 0), 0.0);
}

TEST(PoreFilter, DefaultsFromGrainRadius) {
  const auto o = PoreFilterOptions::from_grain_radius(20);
  EXPECT_EQ(o.max_volume_vox, std::llround(0.02 * 4.0 / 3.0 * std::numbers::pi * 8000));
  EXPECT_DOUBLE_EQ(o.min_sphericity, 0.5);
  EXPECT_FALSE(o.describe().empty());
  EXPECT_THROW(PoreFilterOptions::from_grain_radius(0), UsageError);
}

TEST(PoreFilter, FillsSmallSphericalPoresInsideAGrain) {
  auto m = Volume<uint8_t>::filled(Shape{40, 40, 40}, 0);
  draw_ball(m, 20, 20, 20, 14);
  const int64_t solid = test::count_value(m, 1);
  draw_ball(m, 20, 20, 20, 2.5, 0);
  draw_ball(m, 14, 20, 22, 2, 0);
  draw_ball(m, 24, 14, 18, 1.5, 0);
  m(20, 27, 20) = 0;  // one-voxel pore
  Volume<uint32_t> scratch;
  const auto r = fill_pores(m, scratch, PoreFilterOptions::from_grain_radius(14));
  EXPECT_EQ(r.void_components, 5);
  EXPECT_EQ(r.enclosed, 4);
  EXPECT_EQ(r.filled, 4);
  EXPECT_EQ(test::count_value(m, 1), solid);  // the grain is whole again
}

TEST(PoreFilter, KeepsLargeOrFlatEnclosedVoids) {
  auto m = Volume<uint8_t>::filled(Shape{48, 48, 48}, 0);
  draw_ball(m, 24, 24, 24, 20);
  // A large cavity (radius 7: ~1400 voxels > 2 % of the grain, 670).
  draw_ball(m, 24, 24, 14, 7, 0);
  // An enclosed flat crack: a 1-voxel disc of radius 8 at x = 34.
  for (int64_t k = 0; k < 48; ++k)
    for (int64_t j = 0; j < 48; ++j)
      if ((k - 24) * (k - 24) + (j - 24) * (j - 24) <= 64) m(k, j, 34) = 0;
  const auto before = m.clone();
  Volume<uint32_t> scratch;
  const auto r = fill_pores(m, scratch, PoreFilterOptions::from_grain_radius(20));
  EXPECT_EQ(r.enclosed, 2);
  EXPECT_EQ(r.filled, 0);
  for (int64_t i = 0; i < m.size(); ++i) ASSERT_EQ(m[i], before[i]);
}

TEST(PoreFilter, NeverFillsTheGapOfASplitGrainNorBorderVoids) {
  auto m = Volume<uint8_t>::filled(Shape{40, 40, 41}, 0);
  draw_ball(m, 20, 20, 20, 15);
  test::cut_slab_x(m, 20, 1);  // 1-voxel gap through the whole grain: open to the outside
  m(0, 0, 0) = 0;
  const auto before = m.clone();
  Volume<uint32_t> scratch;
  // Even with criteria that accept anything, voids reaching the border stay.
  const auto r = fill_pores(m, scratch, {1 << 30, 0.0});
  EXPECT_EQ(r.filled, 0);
  for (int64_t i = 0; i < m.size(); ++i) ASSERT_EQ(m[i], before[i]);
}

TEST(PoreFilter, EnclosedGapBetweenHalvesIsFlat) {
  // Two halves of a split grain inside a solid-free box, the gap sealed at
  // its rim by a thin solid ring: enclosed, but flat -> not filled.
  auto m = Volume<uint8_t>::filled(Shape{40, 40, 41}, 0);
  draw_ball(m, 20, 20, 20, 15);
  for (int64_t k = 0; k < 40; ++k)
    for (int64_t j = 0; j < 40; ++j) {
      const double rr = std::hypot(double(k - 20), double(j - 20));
      if (rr <= 12) m(k, j, 20) = 0;  // the gap stays inside the ball's rim
    }
  Volume<uint32_t> scratch;
  const auto r = fill_pores(m, scratch, PoreFilterOptions::from_grain_radius(15));
  EXPECT_EQ(r.enclosed, 1);
  EXPECT_EQ(r.filled, 0);
}

TEST(PoreFilter, EmptyAndAllSolid) {
  Volume<uint32_t> scratch;
  auto e = Volume<uint8_t>::filled(Shape{5, 5, 5}, 0);
  EXPECT_EQ(fill_pores(e, scratch, {100, 0.5}).filled, 0);
  auto f = Volume<uint8_t>::filled(Shape{5, 5, 5}, 1);
  EXPECT_EQ(fill_pores(f, scratch, {100, 0.5}).void_components, 0);
}

}  // namespace
}  // namespace tg

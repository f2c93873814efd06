#include "segmentation/pore_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <omp.h>

#include "core/errors.hpp"
#include "fixtures.hpp"
#include "segmentation/connected_components.hpp"

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

// Oracle: the void labelled voxel by voxel (connected_components, itself
// checked against a flood fill), faces counted voxel by voxel, the rule
// applied per label. Random solids full of small enclosed voids, criteria
// that fill some and keep others, 1-3 threads: same counts, same mask.
TEST(PoreFilter, MatchesAVoxelByVoxelOracle) {
  const int before = omp_get_max_threads();
  std::mt19937 rng(21);
  for (double p_void : {0.08, 0.25}) {
    Volume<uint8_t> m0(Shape{23, 29, 31});
    std::bernoulli_distribution v(p_void);
    for (auto& x : m0.span()) x = v(rng) ? 0 : 1;
    const PoreFilterOptions o{6, 0.3};
    // The oracle.
    Volume<uint8_t> want = m0.clone();
    Volume<uint32_t> lab;
    const auto cc = connected_components(m0, lab, {6, Phase::zero, 1});
    const Shape s = m0.shape();
    std::vector<int64_t> faces(cc.count + 1, 0);
    std::vector<uint8_t> border(cc.count + 1, 0);
    for (int64_t k = 0; k < s.nz; ++k)
      for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
          const uint32_t l = lab(k, j, i);
          if (!l) continue;
          if (k == 0 || j == 0 || i == 0 || k + 1 == s.nz || j + 1 == s.ny || i + 1 == s.nx) {
            border[l] = 1;
            continue;
          }
          faces[l] += m0(k - 1, j, i) + m0(k + 1, j, i) + m0(k, j - 1, i) + m0(k, j + 1, i) + m0(k, j, i - 1) + m0(k, j, i + 1);
        }
    PoreFilterResult r0;
    r0.void_components = cc.count;
    std::vector<uint8_t> fill(cc.count + 1, 0);
    for (uint32_t l = 1; l <= cc.count; ++l) {
      if (border[l]) continue;
      ++r0.enclosed;
      if (cc.sizes[l] <= o.max_volume_vox && voxel_sphericity(cc.sizes[l], faces[l]) >= o.min_sphericity) {
        fill[l] = 1;
        ++r0.filled;
        r0.filled_voxels += cc.sizes[l];
      }
    }
    for (int64_t i = 0; i < want.size(); ++i)
      if (fill[lab[i]]) want[i] = 1;
    ASSERT_GT(r0.filled, 5) << p_void;
    ASSERT_GT(r0.enclosed, r0.filled) << p_void;
    for (int threads : {1, 2, 3}) {
      omp_set_num_threads(threads);
      Volume<uint8_t> m = m0.clone();
      const auto r = fill_pores(m, o);
      EXPECT_EQ(r.void_components, r0.void_components) << p_void << ", " << threads << " threads";
      EXPECT_EQ(r.enclosed, r0.enclosed) << p_void << ", " << threads << " threads";
      EXPECT_EQ(r.filled, r0.filled) << p_void << ", " << threads << " threads";
      EXPECT_EQ(r.filled_voxels, r0.filled_voxels) << p_void << ", " << threads << " threads";
      for (int64_t i = 0; i < m.size(); ++i) ASSERT_EQ(m[i], want[i]) << "voxel " << i << ", " << threads << " threads";
    }
  }
  omp_set_num_threads(before);
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
  const auto r = fill_pores(m, PoreFilterOptions::from_grain_radius(14));
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
  const auto r = fill_pores(m, PoreFilterOptions::from_grain_radius(20));
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
  // Even with criteria that accept anything, voids reaching the border stay.
  const auto r = fill_pores(m, {1 << 30, 0.0});
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
  const auto r = fill_pores(m, PoreFilterOptions::from_grain_radius(15));
  EXPECT_EQ(r.enclosed, 1);
  EXPECT_EQ(r.filled, 0);
}

TEST(PoreFilter, EmptyAndAllSolid) {
  auto e = Volume<uint8_t>::filled(Shape{5, 5, 5}, 0);
  EXPECT_EQ(fill_pores(e, {100, 0.5}).filled, 0);
  auto f = Volume<uint8_t>::filled(Shape{5, 5, 5}, 1);
  EXPECT_EQ(fill_pores(f, {100, 0.5}).void_components, 0);
}

}  // namespace
}  // namespace tg

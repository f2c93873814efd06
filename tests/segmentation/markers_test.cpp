#include "segmentation/markers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <limits>
#include <random>
#include <set>

#include <omp.h>

#include "core/errors.hpp"
#include "fixtures.hpp"
#include "segmentation/distance_transform.hpp"
#include "segmentation/watershed.hpp"

namespace tg {
namespace {

using test::draw_ball;

uint32_t markers_of(const Volume<uint8_t>& m, double h, Volume<uint32_t>& mk) {
  Volume<float> d;
  distance_transform(m, d);
  return find_markers(d, m, mk, {h, 26});
}

TEST(Markers, OneMarkerPerBallDespitePlateaus) {
  auto m = Volume<uint8_t>::filled(Shape{30, 30, 30}, 0);
  draw_ball(m, 14.5, 14.5, 14.5, 11);  // centre between voxels: an 8-voxel top plateau
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 1.0, mk), 1u);
  EXPECT_EQ(mk(14, 14, 14), 1u);
  EXPECT_EQ(mk(15, 15, 15), 1u);
}

TEST(Markers, TouchingPairDependsOnDepth) {
  // Balls of radius 10, centres 18 apart: neck radius sqrt(100 - 81) ~ 4.4,
  // so each peak has a dynamic of about 10 - 4.4 ~ 5.6 (voxelised: ~5-6).
  auto m = Volume<uint8_t>::filled(Shape{26, 26, 44}, 0);
  draw_ball(m, 12.5, 12.5, 12.5, 10);
  draw_ball(m, 12.5, 12.5, 30.5, 10);
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 2.0, mk), 2u);
  EXPECT_NE(mk(12, 12, 12), mk(12, 12, 30));
  EXPECT_EQ(markers_of(m, 8.0, mk), 1u);  // deeper than the neck: one grain
}

TEST(Markers, SplitHalvesOneVoxelApartKeepTwoMarkers) {
  // The usual min-distance rule (~ one radius) would keep one of these two peaks.
  auto m = Volume<uint8_t>::filled(Shape{30, 30, 31}, 0);
  draw_ball(m, 15, 15, 15, 12);
  test::cut_slab_x(m, 15, 1);
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 100.0, mk), 2u);  // even an absurd depth cannot merge components
}

TEST(Markers, EveryComponentGetsOneIncludingSingleVoxels) {
  auto m = Volume<uint8_t>::filled(Shape{9, 9, 9}, 0);
  m(0, 0, 0) = 1;  // corner of the volume
  m(4, 4, 4) = 1;
  m(8, 8, 2) = 1;
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 2.0, mk), 3u);
  std::set<uint32_t> got{mk(0, 0, 0), mk(4, 4, 4), mk(8, 8, 2)};
  EXPECT_EQ(got, (std::set<uint32_t>{1, 2, 3}));  // raster order
}

// With h = 0 the markers are the regional maxima: plateaus (connected sets
// of one height, within the solid) with no strictly higher neighbour.
// Oracle: each plateau grown breadth-first from its first voxel in raster
// order, kept if nothing next to it is higher. Random heights with many
// ties and plateaus cut by the border; every connectivity and 1-3 threads.
TEST(Markers, ZeroDepthGivesTheRegionalMaximaOfAnOracle) {
  const int before = omp_get_max_threads();
  const Shape s{9, 11, 13};
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> height(1, 8);
  std::bernoulli_distribution solid_p(0.8);
  Volume<uint8_t> m(s);
  Volume<float> d(s);
  for (int64_t i = 0; i < m.size(); ++i) {
    m[i] = solid_p(rng) ? 1 : 0;
    d[i] = m[i] ? float(height(rng)) : 0.0f;
  }
  for (int conn : {6, 18, 26}) {
    const int maxd2 = conn == 6 ? 1 : conn == 18 ? 2 : 3;
    std::vector<uint32_t> want(size_t(m.size()), 0);
    std::vector<uint8_t> seen(size_t(m.size()), 0);
    uint32_t count = 0;
    for (int64_t start = 0; start < m.size(); ++start) {
      if (!m[start] || seen[size_t(start)]) continue;
      std::vector<int64_t> plateau{start};
      seen[size_t(start)] = 1;
      bool higher = false;
      for (size_t h = 0; h < plateau.size(); ++h) {
        const auto [k, j, i] = s.coords(plateau[h]);
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int d2 = dz * dz + dy * dy + dx * dx;
              if (d2 == 0 || d2 > maxd2 || !s.contains(k + dz, j + dy, i + dx)) continue;
              const int64_t y = s.index(k + dz, j + dy, i + dx);
              if (!m[y]) continue;
              if (d[y] > d[start]) higher = true;
              if (d[y] == d[start] && !seen[size_t(y)]) {
                seen[size_t(y)] = 1;
                plateau.push_back(y);
              }
            }
      }
      if (higher) continue;
      ++count;
      for (int64_t v : plateau) want[size_t(v)] = count;
    }
    ASSERT_GT(count, 10u) << "conn " << conn;
    for (int threads : {1, 2, 3}) {
      omp_set_num_threads(threads);
      Volume<uint32_t> mk;
      ASSERT_EQ(find_markers(d, m, mk, {0.0, conn}), count) << "conn " << conn << ", " << threads << " threads";
      for (int64_t i = 0; i < m.size(); ++i)
        ASSERT_EQ(mk[i], want[size_t(i)]) << "conn " << conn << ", " << threads << " threads, voxel " << i;
    }
  }
  omp_set_num_threads(before);
}

// The segment chain finds markers and levels on the 16-bit fixed-point map
// (to_fixed_point): the float path is the reference.
TEST(Markers, FixedPointMapGivesTheFloatMapsMarkersAndLevels) {
  auto m = Volume<uint8_t>::filled(Shape{48, 48, 64}, 0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(6, 42), rad(4, 11);
  for (int b = 0; b < 14; ++b) draw_ball(m, pos(rng), pos(rng), pos(rng) + 8, rad(rng));
  test::cut_slab_x(m, 31, 1);  // a split: two peaks a voxel apart
  Volume<float> d;
  distance_transform(m, d);
  for (const double h : {0.7, 1.5, 3.0}) {
    Volume<uint32_t> want, got;
    const uint32_t nwant = find_markers(d, want, {h, 26});
    const FixedDistance fx = to_fixed_point(d.clone());
    EXPECT_EQ(fx.per_unit, 256.0);
    const uint32_t ngot = find_markers(fx, got, {h, 26});
    EXPECT_GT(nwant, 3u);
    ASSERT_EQ(ngot, nwant) << "h " << h;
    // Same markers, same numbering; a cap's rim may gain or lose the voxels
    // whose distance lies within 1/256 voxel of top - h.
    int64_t differ = 0, cap = 0;
    for (int64_t i = 0; i < d.size(); ++i) {
      cap += want[i] != 0;
      differ += want[i] != got[i];
      if (want[i] && got[i]) {
        ASSERT_EQ(want[i], got[i]) << "h " << h;
      }
    }
    EXPECT_LE(differ, cap / 50) << "h " << h;
  }
  double qf = 0, qx = 0;
  const Volume<uint8_t> lf = quantise_levels(d.clone(), 4.0, qf);
  const Volume<uint8_t> lx = quantise_levels(to_fixed_point(d.clone()), 4.0, qx);
  EXPECT_EQ(qf, qx);
  int64_t off = 0;
  for (int64_t i = 0; i < d.size(); ++i) {
    ASSERT_LE(std::abs(int(lf[i]) - int(lx[i])), 1);
    ASSERT_EQ(lf[i] == 0, lx[i] == 0);
    off += lf[i] != lx[i];
  }
  EXPECT_LE(off, d.size() / 1000);  // only where d * 4 lies within 1/128 of an integer
}

TEST(Markers, FixedPointKeepsTheSolidAndScalesDeepMaps) {
  Volume<float> d = Volume<float>::filled(Shape{1, 1, 4}, 0.f);
  d[1] = 1e-3f;   // a dim voxel: still solid
  d[2] = 2.5f;
  d[3] = 1000.f;  // deep: 64 units per voxel, the largest power of two with 1000 u <= 65535
  const FixedDistance fx = to_fixed_point(d.clone());
  EXPECT_EQ(fx.per_unit, 64.0);
  EXPECT_EQ(fx.dmax, 1000.f);
  EXPECT_EQ(fx.map[0], 0);
  EXPECT_EQ(fx.map[1], 1);
  EXPECT_EQ(fx.map[2], 160);
  EXPECT_EQ(fx.map[3], 64000);
  const FixedDistance given = to_fixed_point(std::move(d), 128.0);  // a slab's units, given: the deep value clamps
  EXPECT_EQ(given.map[2], 320);
  EXPECT_EQ(given.map[3], 65535);
  EXPECT_EQ(fixed_point_units(255.0f), 256.0);
  EXPECT_EQ(fixed_point_units(256.0f), 128.0);
  Volume<float> bad = Volume<float>::filled(Shape{1, 1, 2}, 1.f);
  bad[1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(to_fixed_point(std::move(bad)), UsageError);
}

TEST(Markers, EmptyVolumeAndBadArguments) {
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(Volume<uint8_t>::filled(Shape{4, 4, 4}, 0), 1.0, mk), 0u);
  Volume<float> d = Volume<float>::filled(Shape{2, 2, 2}, 1.f);
  EXPECT_THROW(find_markers(d, Volume<uint8_t>::filled(Shape{2, 2, 3}, 1), mk), UsageError);
  EXPECT_THROW(find_markers(d, Volume<uint8_t>::filled(Shape{2, 2, 2}, 1), mk, {-1.0, 26}), UsageError);
}

}  // namespace
}  // namespace tg

#include "segmentation/watershed.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <limits>
#include <queue>
#include <random>
#include <set>

#include "core/errors.hpp"
#include "fixtures.hpp"
#include "segmentation/distance_transform.hpp"
#include "segmentation/markers.hpp"

namespace tg {
namespace {

using test::draw_ball;

Volume<uint32_t> run(const Volume<uint8_t>& m, bool lines, double h = 2.0) {
  Volume<float> d;
  distance_transform(m, d);
  Volume<uint32_t> lab;
  find_markers(d, m, lab, {h, 26});
  watershed(d, m, lab, {lines, 26, 4.0});
  return lab;
}

std::set<uint32_t> labels_in(const Volume<uint32_t>& lab) {
  std::set<uint32_t> s;
  for (auto l : lab.span())
    if (l) s.insert(l);
  return s;
}

Volume<uint8_t> touching_pair() {
  auto m = Volume<uint8_t>::filled(Shape{26, 26, 44}, 0);
  draw_ball(m, 12.5, 12.5, 12.5, 10);
  draw_ball(m, 12.5, 12.5, 30.5, 10);  // symmetric about the plane x = 21.5
  return m;
}

TEST(Watershed, TouchingBallsSplitAtTheNeckWithALine) {
  const auto m = touching_pair();
  const auto lab = run(m, true);
  ASSERT_EQ(labels_in(lab).size(), 2u);
  const uint32_t a = lab(12, 12, 12), b = lab(12, 12, 30);
  ASSERT_NE(a, b);
  int64_t line = 0;
  for (int64_t k = 0; k < 26; ++k)
    for (int64_t j = 0; j < 26; ++j)
      for (int64_t i = 0; i < 44; ++i) {
        const uint32_t l = lab(k, j, i);
        if (!m(k, j, i)) {
          EXPECT_EQ(l, 0u);
          continue;
        }
        if (l == 0) {
          ++line;
          EXPECT_TRUE(i == 21 || i == 22) << "line voxel off the neck at x = " << i;
        } else {
          EXPECT_EQ(l, i <= 21 ? a : b) << "voxel (" << k << "," << j << "," << i << ")";
        }
      }
  // The neck disc has radius ~4.4 voxels: ~60 voxels in one plane.
  EXPECT_GT(line, 40);
  EXPECT_LT(line, 2 * 90);
}

TEST(Watershed, WithoutLinesEverySolidVoxelIsLabelled) {
  const auto m = touching_pair();
  const auto lab = run(m, false);
  EXPECT_EQ(labels_in(lab).size(), 2u);
  for (int64_t i = 0; i < m.size(); ++i) EXPECT_EQ(lab[i] != 0, m[i] != 0);
  // Symmetric pair: the split is at the mid-plane (x <= 21 vs >= 22).
  EXPECT_EQ(lab(12, 12, 21), lab(12, 12, 12));
  EXPECT_EQ(lab(12, 12, 22), lab(12, 12, 30));
}

TEST(Watershed, SplitHalvesOneAndTwoVoxelsApartAreTwoParticles) {
  for (int64_t gap : {1, 2}) {
    auto m = Volume<uint8_t>::filled(Shape{30, 30, 32}, 0);
    draw_ball(m, 15, 15, 15.5, 12);
    test::cut_slab_x(m, 15, gap);
    const auto lab = run(m, true, 3.0);
    EXPECT_EQ(labels_in(lab).size(), 2u) << "gap " << gap;
    EXPECT_NE(lab(15, 15, 10), lab(15, 15, 20));
  }
}

TEST(Watershed, GrainsTouchingTheBorderAndSingleVoxels) {
  auto m = Volume<uint8_t>::filled(Shape{20, 20, 20}, 0);
  draw_ball(m, 0, 10, 10, 8);  // cut in half by the z = 0 face
  m(19, 19, 19) = 1;           // a 1-voxel grain in the corner
  m(15, 2, 2) = 1;             // and one inside
  const auto lab = run(m, true);
  EXPECT_EQ(labels_in(lab).size(), 3u);
  int64_t big = 0;
  for (int64_t i = 0; i < m.size(); ++i) big += (lab[i] != 0 && lab[i] == lab(0, 10, 10));
  EXPECT_EQ(big, test::count_value(m, 1) - 2);  // the half ball is one whole particle
  EXPECT_NE(lab(19, 19, 19), 0u);
  EXPECT_NE(lab(15, 2, 2), 0u);
}

TEST(Watershed, EmptyVolumeAndShapeMismatch) {
  auto m = Volume<uint8_t>::filled(Shape{5, 5, 5}, 0);
  EXPECT_TRUE(labels_in(run(m, true)).empty());
  Volume<float> d = Volume<float>::filled(Shape{5, 5, 5}, 0.f);
  auto lab = Volume<uint32_t>::filled(Shape{5, 5, 4}, 0);
  EXPECT_THROW(watershed(d, m, lab), UsageError);
}

TEST(Watershed, LevelsAreCoarsenedToFitOneByte) {
  // d = 0.5 .. 100 voxels along x: at 4 levels per unit the top level would
  // be 400, so q falls to 254 / 100 and every level still orders like d.
  const Shape s{1, 1, 200};
  Volume<float> d(s);
  auto m = Volume<uint8_t>::filled(s, 1);
  for (int64_t i = 0; i < 200; ++i) d[i] = 0.5f * float(i + 1);
  m[7] = 0;  // void stays 0
  EXPECT_DOUBLE_EQ(quantise_levels(d, m, 4.0), 2.54);
  EXPECT_EQ(m[7], 0);
  for (int64_t i = 1; i < 200; ++i)
    if (i != 7 && i != 8) {
      EXPECT_GE(m[i], m[i - 1]) << i;
    }
  EXPECT_EQ(m[199], 255);
  EXPECT_EQ(m[0], 1 + int(0.5 * 2.54));
  // Small distances keep the requested resolution.
  Volume<uint8_t> m2 = Volume<uint8_t>::filled(s, 1);
  for (int64_t i = 0; i < 200; ++i) d[i] = 0.25f * float(i % 40);
  EXPECT_DOUBLE_EQ(quantise_levels(d, m2, 4.0), 4.0);
  EXPECT_EQ(m2[39], 1 + 39);
}

// The levels written over the float map's own storage (in rounds, so that
// no float is overwritten before it is read) equal the levels of the mask
// version, with the solid where the map is > 0; 3 x 10^5 voxels make
// several parallel rounds after the serial start.
TEST(Watershed, LevelsOverTheMapEqualTheLevelsOfTheMask) {
  const Shape s{60, 70, 80};
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(0.0f, 30.0f);
  for (double per_unit : {4.0, 20.0}) {  // 20: coarsened to 254 / dmax
    Volume<float> d(s);
    auto m = Volume<uint8_t>::filled(s, 1);
    for (int64_t i = 0; i < d.size(); ++i) {
      d[i] = (i % 7 == 3) ? 0.0f : 1.0f + u(rng);
      if (d[i] == 0.0f) m[i] = 0;
    }
    const double q_mask = quantise_levels(d, m, per_unit);
    double q_map = 0;
    const float* storage = d.data();
    const Volume<uint8_t> lev = quantise_levels(std::move(d), per_unit, q_map);
    EXPECT_EQ(static_cast<const void*>(lev.data()), static_cast<const void*>(storage));  // no new volume
    EXPECT_TRUE(d.empty());
    ASSERT_EQ(lev.shape(), s);
    EXPECT_DOUBLE_EQ(q_map, q_mask);
    for (int64_t i = 0; i < lev.size(); ++i) ASSERT_EQ(lev[i], m[i]) << "voxel " << i << ", " << per_unit;
  }
  Volume<float> bad = Volume<float>::filled(Shape{2, 2, 2}, 1.0f);
  bad[3] = std::numeric_limits<float>::quiet_NaN();
  double q = 0;
  EXPECT_THROW(quantise_levels(std::move(bad), 4.0, q), UsageError);
}

// The flood shares each round among threads by slabs of slices; the slabs
// are fixed by the shape, so the labels must not depend on the thread
// count, and lines must stay whole (no two labels touch) where slabs meet.
TEST(Watershed, LabelsDoNotDependOnTheThreadCount) {
  const Shape s{120, 96, 104};
  auto m = Volume<uint8_t>::filled(s, 0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uz(0, 120), uy(0, 96), ux(0, 104), ur(6, 13);
  for (int b = 0; b < 90; ++b) draw_ball(m, uz(rng), uy(rng), ux(rng), ur(rng));
  const int before = omp_get_max_threads();
  for (bool lines : {true, false}) {
    std::vector<Volume<uint32_t>> out;
    for (int t : {1, 2, 3}) {
      omp_set_num_threads(t);
      out.push_back(run(m, lines, 1.0));
    }
    omp_set_num_threads(before);
    ASSERT_GT(labels_in(out[0]).size(), 20u);
    for (size_t r = 1; r < out.size(); ++r)
      ASSERT_TRUE(std::equal(out[0].span().begin(), out[0].span().end(), out[r].span().begin()))
          << "labels differ with " << r + 1 << " threads (lines " << lines << ")";
    if (!lines) continue;
    const Volume<uint32_t>& lab = out[0];
    for (int64_t k = 0; k + 1 < s.nz; ++k)
      for (int64_t j = 1; j + 1 < s.ny; ++j)
        for (int64_t i = 1; i + 1 < s.nx; ++i) {
          const uint32_t a = lab[s.index(k, j, i)];
          if (!a) continue;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const uint32_t b = lab[s.index(k + 1, j + dy, i + dx)];
              ASSERT_TRUE(b == 0 || b == a) << "labels " << a << " and " << b << " touch across slices " << k
                                            << " and " << k + 1;
            }
        }
  }
}

// Invariants of a marker-controlled watershed, checked by brute force on
// random packings of overlapping balls: every marker keeps its label; every
// label is one 26-connected region holding its marker; with lines, no two
// labels touch and every solid voxel is labelled or a line next to two
// labels (or cut off); without lines every solid voxel connected to a
// marker is labelled.
TEST(Watershed, RandomPackingsKeepTheWatershedInvariants) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 4; ++trial) {
    const Shape s{40, 36, 44};
    auto m = Volume<uint8_t>::filled(s, 0);
    std::uniform_real_distribution<double> uz(0, 40), uy(0, 36), ux(0, 44), ur(4, 8);
    for (int b = 0; b < 14; ++b) draw_ball(m, uz(rng), uy(rng), ux(rng), ur(rng));
    Volume<float> d;
    distance_transform(m, d);
    for (bool lines : {true, false}) {
      Volume<uint32_t> mk;
      const uint32_t nmk = find_markers(d, m, mk, {1.0, 26});
      Volume<uint32_t> lab = mk.clone();
      watershed(d, m, lab, {lines, 26, 4.0});
      const int64_t n = s.voxels();
      for (int64_t i = 0; i < n; ++i) {
        if (mk[i]) {
          ASSERT_EQ(lab[i], mk[i]);
        }
        if (!m[i]) {
          ASSERT_EQ(lab[i], 0u);
        }
      }
      // Connectivity of each label from its marker, and label contacts.
      std::vector<uint8_t> seen(size_t(n), 0);
      for (int64_t i = 0; i < n; ++i) {
        if (!mk[i] || seen[size_t(i)]) continue;
        std::queue<int64_t> q;
        q.push(i);
        seen[size_t(i)] = 1;
        while (!q.empty()) {
          const auto [k, j, x] = s.coords(q.front());
          q.pop();
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                if (!s.contains(k + dz, j + dy, x + dx)) continue;
                const int64_t y = s.index(k + dz, j + dy, x + dx);
                if (lines && lab[y] && lab[y] != mk[i]) {
                  FAIL() << "labels " << lab[y] << " and " << mk[i] << " touch";
                }
                if (lab[y] == mk[i] && !seen[size_t(y)]) seen[size_t(y)] = 1, q.push(y);
              }
        }
      }
      std::set<uint32_t> kept;
      for (int64_t i = 0; i < n; ++i)
        if (lab[i]) {
          ASSERT_TRUE(seen[size_t(i)]) << "label " << lab[i] << " is not connected to its marker";
          kept.insert(lab[i]);
        }
      EXPECT_EQ(kept.size(), size_t(nmk));
      if (!lines) {
        // Every solid voxel 26-connected (through solid) to a marker is labelled.
        for (int64_t i = 0; i < n; ++i)
          if (m[i] && !lab[i]) {
            const auto [k, j, x] = s.coords(i);
            for (int dz = -1; dz <= 1; ++dz)
              for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                  if (s.contains(k + dz, j + dy, x + dx)) {
                    ASSERT_EQ(lab(k + dz, j + dy, x + dx), 0u) << "an unlabelled solid voxel next to a label";
                  }
          }
      }
    }
  }
}

}  // namespace
}  // namespace tg

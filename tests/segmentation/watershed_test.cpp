#include "segmentation/watershed.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace tg

#include "segmentation/merge_labels.hpp"

#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "fixtures.hpp"

namespace tg {
namespace {

using test::draw_ball;

// A ball of radius 10 cut by a line through its centre plane x = 15.
struct CutBall {
  Volume<uint8_t> solid = Volume<uint8_t>::filled(Shape{25, 25, 31}, 0);
  Volume<uint32_t> lab = Volume<uint32_t>::filled(Shape{25, 25, 31}, 0);
  explicit CutBall(int64_t cut_x) {
    draw_ball(solid, 12, 12, 15, 10);
    for (int64_t i = 0; i < solid.size(); ++i) {
      if (!solid[i]) continue;
      const int64_t x = solid.shape().coords(i)[2];
      lab[i] = x < cut_x ? 3 : x > cut_x ? 7 : 0;
    }
  }
};

TEST(MergeLabels, PiecesOfOneGrainAcrossAWideLineAreMerged) {
  CutBall c(15);  // interface ~ pi 10^2 = 314 >> 0.5 pi r^2 of a half (r ~ 7.9)
  const auto r = merge_oversegmented(c.lab, c.solid);
  EXPECT_EQ(r.touching_pairs, 1);
  EXPECT_EQ(r.merges, 1);
  for (int64_t i = 0; i < c.lab.size(); ++i) EXPECT_EQ(c.lab[i], c.solid[i] ? 3u : 0u);  // line filled too
}

TEST(MergeLabels, RatioIsTunable) {
  CutBall c(15);
  // interface/(pi r^2) ~ 314/196 ~ 1.6: a ratio of 3 keeps them apart.
  EXPECT_EQ(merge_oversegmented(c.lab, c.solid, {3.0}).merges, 0);
  CutBall e(22);  // a cap of ~3 voxels height: small piece, interface ~ pi (10^2 - 7^2) ~ 160
  EXPECT_EQ(merge_oversegmented(e.lab, e.solid, {0.5}).merges, 1);
}

TEST(MergeLabels, SmallContactBetweenGrainsIsKept) {
  // Two balls radius 10, touching through a neck of radius ~4.4 (as the
  // watershed leaves them): interface ~ 60, far below pi 10^2.
  Volume<uint8_t> solid = Volume<uint8_t>::filled(Shape{26, 26, 44}, 0);
  draw_ball(solid, 12.5, 12.5, 12.5, 10);
  draw_ball(solid, 12.5, 12.5, 30.5, 10);
  auto lab = Volume<uint32_t>::filled(solid.shape(), 0);
  for (int64_t i = 0; i < solid.size(); ++i)
    if (solid[i]) {
      const int64_t x = solid.shape().coords(i)[2];
      lab[i] = x <= 20 ? 1 : x >= 23 ? 2 : 0;  // a 2-voxel line region at the neck
    }
  const auto before = lab.clone();
  const auto r = merge_oversegmented(lab, solid);
  EXPECT_EQ(r.merges, 0);
  for (int64_t i = 0; i < lab.size(); ++i) ASSERT_EQ(lab[i], before[i]);
}

TEST(MergeLabels, DirectFacesCountWithoutLines) {
  Volume<uint8_t> solid = Volume<uint8_t>::filled(Shape{4, 4, 4}, 1);
  auto lab = Volume<uint32_t>::filled(solid.shape(), 0);
  for (int64_t i = 0; i < lab.size(); ++i) lab[i] = solid.shape().coords(i)[2] < 2 ? 1 : 2;
  // 16 faces between two 32-voxel labels; pi r^2 with r = (3*32/4pi)^(1/3) ~ 12.2.
  EXPECT_EQ(merge_oversegmented(lab, solid, {1.0}).merges, 1);
  EXPECT_EQ(lab[63], 1u);
}

TEST(MergeLabels, ShapeMismatch) {
  auto lab = Volume<uint32_t>::filled(Shape{2, 2, 2}, 0);
  EXPECT_THROW(merge_oversegmented(lab, Volume<uint8_t>::filled(Shape{2, 2, 1}, 0)), UsageError);
}

}  // namespace
}  // namespace tg

#include "segmentation/merge_labels.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <numbers>
#include <vector>

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

// Thin walls (merge_thin_walls). A bowl: the shell between radii 11 and 14
// around (20, 20, 20), open above z 24, cut by the watershed into three
// pieces at azimuths 0, 120 and 240 degrees (a line voxel thick, as bright
// as the wall: one wall); beside it a second wall, a slab 3 voxels thick
// at x 36..38, meeting piece 1 across a dim line (grey 22000: a contact's
// partial volume), and a ball (thick) meeting piece 2 across a bright
// line. Grey: void 10000, wall and lines 30000 unless said; threshold
// 20000, bright from 25000.
Box whole(const Shape& s) { return Box{0, 0, 0, s}; }

// The bounding boxes of labels 1..4 (the thin ones of Walls).
std::vector<Box> boxes_of_walls(const Volume<uint32_t>& lab) {
  std::vector<std::array<int64_t, 6>> b(5, {INT64_MAX, INT64_MAX, INT64_MAX, -1, -1, -1});
  for (int64_t i = 0; i < lab.size(); ++i) {
    const uint32_t l = lab[i];
    if (l < 1 || l > 4) continue;
    const auto c = lab.shape().coords(i);
    for (int a = 0; a < 3; ++a) b[l][a] = std::min(b[l][a], c[a]), b[l][a + 3] = std::max(b[l][a + 3], c[a]);
  }
  std::vector<Box> out;
  for (uint32_t l = 1; l <= 4; ++l)
    out.push_back(Box{b[l][0], b[l][1], b[l][2], Shape{b[l][3] - b[l][0] + 1, b[l][4] - b[l][1] + 1, b[l][5] - b[l][2] + 1}});
  return out;
}

struct Walls {
  Shape s{40, 40, 48};
  Volume<uint32_t> lab = Volume<uint32_t>::filled(s, 0u);
  Volume<uint8_t> grey = Volume<uint8_t>::filled(s, 0);  // grey / 200: 50 void, 150 solid
  int64_t bowl_lines = 0;
  Walls() {
    for (int64_t k = 0; k < s.nz; ++k)
      for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
          const double dz = double(k) - 20, dy = double(j) - 20, dx = double(i) - 20;
          const double r = std::sqrt(dz * dz + dy * dy + dx * dx);
          uint8_t g = 50;
          uint32_t l = 0;
          if (r >= 11 && r <= 14 && k <= 24) {
            // the sector by azimuth; a voxel within half a voxel of a cut is a line voxel
            const double az = std::atan2(dy, dx) * 180 / std::numbers::pi + 180;  // 0..360
            const double arc = std::max(1.0, std::hypot(dy, dx)) * std::numbers::pi / 180;  // voxels per degree
            bool line = false;
            for (const double cut : {0.0, 120.0, 240.0, 360.0}) line |= std::abs(az - cut) * arc < 0.5;
            g = 150;
            l = line ? 0 : 1 + uint32_t(az / 120.0) % 3;
            bowl_lines += line;
          } else if (i >= 36 && i <= 38 && k >= 10 && k <= 30 && j >= 10 && j <= 30) {
            g = 150, l = 4;  // the second wall
          } else if (i == 35 && k >= 10 && k <= 30 && j >= 10 && j <= 30) {
            g = 110;  // dim contact between the walls (grey 22000), a line
          }
          grey(k, j, i) = g;
          lab(k, j, i) = l;
        }
    // The ball, radius 6, below the bowl's piece 2 side: joined to it by a bright line voxel layer.
    for (int64_t k = 0; k < s.nz; ++k)
      for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i) {
          const double dz = double(k) - 20, dy = double(j) - 38, dx = double(i) - 8;
          const double r = std::sqrt(dz * dz + dy * dy + dx * dx);
          if (r <= 6 && lab(k, j, i) == 0 && grey(k, j, i) == 50) grey(k, j, i) = 150, lab(k, j, i) = 5;
        }
  }
};

TEST(MergeThinWalls, AWallCutByTheWatershedIsOneLabelAgain) {
  Walls w;
  // Which pieces the test drew: three sectors, the slab, the ball.
  std::vector<int64_t> vol(6, 0);
  for (int64_t i = 0; i < w.lab.size(); ++i) ++vol[w.lab[i]];
  for (uint32_t l = 1; l <= 5; ++l) ASSERT_GT(vol[l], 200) << l;
  const std::vector<uint8_t> thin = {0, 1, 1, 1, 1, 0};  // the ball is not thin
  WallMergeOptions o;
  o.floor = 100, o.bright = 125;  // grey 20000 and 25000 in the code's units
  const auto r = merge_thin_walls(w.lab, w.grey, thin, {whole(w.s)}, o);
  EXPECT_EQ(r.thin_labels, 4);
  EXPECT_EQ(r.merges, 2);  // the three sectors, chained
  std::vector<int64_t> after(6, 0);
  for (int64_t i = 0; i < w.lab.size(); ++i) ++after[w.lab[i]];
  EXPECT_EQ(after[2] + after[3], 0);
  // The bowl's line voxels between two of its pieces joined them; those at
  // the bottom, where the three cuts meet, see three labels and stay lines.
  EXPECT_LE(after[1], vol[1] + vol[2] + vol[3] + w.bowl_lines);
  EXPECT_GE(after[1], vol[1] + vol[2] + vol[3] + w.bowl_lines - 8) << w.bowl_lines << " line voxels";
  EXPECT_EQ(after[4], vol[4]) << "the wall beyond a dim contact stays apart";
  EXPECT_EQ(after[5], vol[5]) << "the ball stays apart (not thin)";
  // Looking only inside the thin labels' boxes (as segment() does) changes nothing.
  Walls w2;
  const auto r2 = merge_thin_walls(w2.lab, w2.grey, thin, boxes_of_walls(w2.lab), o);
  EXPECT_EQ(r2.merges, r.merges);
  EXPECT_EQ(r2.touching_pairs, r.touching_pairs);
  EXPECT_TRUE(std::equal(w2.lab.data(), w2.lab.data() + w2.lab.size(), w.lab.data()));
}

TEST(MergeThinWalls, ADimInterfaceOrTooSmallABrightOneKeepsPiecesApart) {
  Walls w;
  const std::vector<uint8_t> thin = {0, 1, 1, 1, 1, 0};
  WallMergeOptions o;
  o.floor = 100, o.bright = 160;  // nothing is bright: no merge
  EXPECT_EQ(merge_thin_walls(w.lab, w.grey, thin, {whole(w.s)}, o).merges, 0);
  o.bright = 125, o.min_area = 1000;  // the cuts are ~3 x 8 voxels
  EXPECT_EQ(merge_thin_walls(w.lab, w.grey, thin, {whole(w.s)}, o).merges, 0);
  const std::vector<uint8_t> none = {0, 0, 0, 0, 0, 0};
  o.min_area = 9;
  EXPECT_EQ(merge_thin_walls(w.lab, w.grey, none, {whole(w.s)}, o).merges, 0);
}

}  // namespace
}  // namespace tg

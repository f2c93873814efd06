// Face slivers (segmentation/face_slivers.hpp): grains whose centres lie
// outside the scan, cut by its faces a voxel or two from their edge, come
// out as particles (IoU >= 0.5 with the truth: partial volume by 3^3
// supersampling, PSF 0.7 voxel, CNR 13, blur reaching in from outside the
// window); the grains inside keep their labels; slab by slab as whole.
#include <gtest/gtest.h>

#include <vector>

#include "scan_scenes.hpp"
#include "segmentation/segment.hpp"
#include "segmentation/segment_chunked.hpp"

namespace tg {
namespace {

using test::Ball;
using test::best_iou;
using test::render;

auto no_cut = [](double, double, double) { return false; };

// Six slivers of balls of radius 10, one through each face, reaching
// `reach` voxels into a 48^3 window, and grains inside it (the scan's
// histogram needs solid), none touching another.
std::vector<Ball> sliver_scene(double reach) {
  const double r = 10, lo = -r + reach, hi = 48 + r - reach;
  return {{lo, 10, 10, r},  {hi, 38, 12, r}, {12, lo, 36, r}, {36, hi, 36, r}, {36, 12, lo, r}, {12, 36, hi, r},
          {24, 24, 24, 9}, {34, 34, 12, 5}, {12, 12, 34, 5}};
}
constexpr int kSlivers = 6;
const Shape kSliverWindow{48, 48, 48};

// The threshold at the phases' midpoint, where Tsai's lies on a packing
// (this window holds ~5 % solid, and a histogram method puts it at 0.2 of
// the contrast: every label then overflows its grain).
SegmentOptions sliver_options(bool slivers) {
  SegmentOptions o;
  o.grain_radius_vox = 10;
  o.threshold = ThresholdMethod::manual;
  o.manual_threshold = 20000;
  o.face_slivers = slivers;
  return o;
}

struct SliverCount {
  int slivers = 0, with = 0, without = 0;  // truth slivers (>= 8 voxels); matched with / without the step
  double iou_with = 0, iou_without = 0;    // summed over the slivers
};

// The scene imaged with `pad` (test::render), noise seeds `seeds`; the
// grains inside must keep their labels.
SliverCount count_slivers(double reach, int64_t pad, const std::vector<uint64_t>& seeds) {
  SliverCount c;
  for (const uint64_t seed : seeds) {
    const std::vector<Ball> balls = sliver_scene(reach);
    const test::Scene sc = render(kSliverWindow, balls, no_cut, seed, pad);
    const SegmentResult with = segment(sc.grey, sliver_options(true));
    const SegmentResult without = segment(sc.grey, sliver_options(false));
    EXPECT_TRUE(with.face_slivers_used);
    for (int q = 1; q <= kSlivers; ++q) {
      int64_t n = 0;
      for (int64_t i = 0; i < sc.truth.size(); ++i) n += sc.truth[i] == uint32_t(q);
      if (n < 8) continue;  // under the size floor: not a particle to find
      ++c.slivers;
      const double a = best_iou(sc.truth, with.labels, uint32_t(q)), b = best_iou(sc.truth, without.labels, uint32_t(q));
      c.with += a >= 0.5, c.without += b >= 0.5, c.iou_with += a, c.iou_without += b;
    }
    for (uint32_t q = kSlivers + 1; q <= balls.size(); ++q) {
      const double a = best_iou(sc.truth, with.labels, q), b = best_iou(sc.truth, without.labels, q);
      EXPECT_GE(a, 0.85) << "seed " << seed << " grain " << q;
      EXPECT_DOUBLE_EQ(a, b) << "seed " << seed << " grain " << q;
    }
  }
  return c;
}

// Noise seeds 1-3 and reaches 0.6-1.9 were looked at while writing this;
// the assertions run on seeds 21-26.
const std::vector<uint64_t> kSeeds{21, 22, 23, 24, 25, 26};

// Imaged alone (blind_scene.py's way), a sliver under a voxel deep keeps
// its partial volume: dim, half of it under the threshold.
TEST(FaceSlivers, DimSliversOfAWindowImagedAloneBecomeParticles) {
  SliverCount c;
  for (const double reach : {0.7, 0.85}) {
    const SliverCount r = count_slivers(reach, 0, kSeeds);
    c.slivers += r.slivers, c.with += r.with, c.without += r.without;
  }
  ASSERT_GE(c.slivers, 60);
  // Dev seeds: 12 and 17 of 18 at reach 0.7 and 0.85 (a 12-voxel sliver
  // with a voxel or two over the threshold is cleared as a noise speck or
  // has no marker); 0 and 2 of 18 without the step.
  EXPECT_GE(c.with, 7 * c.slivers / 10) << "of " << c.slivers << " slivers";
  EXPECT_LE(c.without, c.slivers / 4) << "the scene should need the step";
}

// In a window of a larger scan the blur brings the grain beyond the face
// in: slivers are as bright as any grain's edge, and their labels must not
// grow past them.
TEST(FaceSlivers, BrightSliversOfALargerScanStayAsThresholded) {
  for (const double reach : {0.85, 1.6}) {
    const SliverCount c = count_slivers(reach, test::kPad, kSeeds);
    ASSERT_GE(c.slivers, 30);
    EXPECT_GE(c.with, c.without) << "reach " << reach;
    EXPECT_GE(c.iou_with, c.iou_without - 0.02 * c.slivers) << "reach " << reach;
  }
}

TEST(FaceSlivers, SameLabelsSlabBySlab) {
  // Two copies of the scene's side slivers and centre grain stacked along z
  // (96 slices; the z = 0 sliver below, the top one above), imaged alone
  // (dim slivers: they grow), segmented whole and in slabs of 16 core
  // slices and 32 of margin: the side slivers of the upper slabs sit in
  // slabs whose z faces are cut, not the scan's.
  const Shape s{96, 48, 48};
  setenv("TOMOGRAIN_QUIET", "1", 0);
  const std::vector<Ball> one = sliver_scene(0.85);
  std::vector<Ball> balls{one[0]};
  for (const double dz : {0.0, 48.0})
    for (const int q : {2, 3, 4, 5, 6}) balls.push_back({one[size_t(q)].z + dz, one[size_t(q)].y, one[size_t(q)].x, one[size_t(q)].r});
  balls.push_back({one[1].z + 48, one[1].y, one[1].x, one[1].r});
  int grown = 0;
  for (uint64_t seed : {21u, 22u}) {
    const test::Scene sc = render(s, balls, no_cut, seed, 0);
    const SegmentResult whole = segment(sc.grey, sliver_options(true));
    grown += int(whole.face_slivers.labels_grown);
    ChunkedResult cr;
    const auto labels = test::segment_slab_by_slab(sc.grey, sliver_options(true), 16, 32, &cr);
    EXPECT_EQ(cr.result.count, whole.count) << "seed " << seed;
    int64_t differ = 0;
    for (int64_t i = 0; i < s.voxels(); ++i) differ += labels[i] != whole.labels[i];
    EXPECT_EQ(differ, 0) << "seed " << seed;
  }
  EXPECT_GE(grown, 10);  // the step ran
}

}  // namespace
}  // namespace tg

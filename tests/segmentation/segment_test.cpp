#include "segmentation/segment.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <algorithm>
#include <random>
#include <set>

#include "core/errors.hpp"
#include "fixtures.hpp"

namespace tg {
namespace {

using test::draw_ball;

// Grey scan of a binary scene: void ~10000, solid ~40000, uniform noise +-3000.
Volume<uint16_t> grey_of(const Volume<uint8_t>& m, unsigned seed = 5) {
  Volume<uint16_t> g(m.shape(), m.geometry());
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-3000, 3000);
  for (int64_t i = 0; i < m.size(); ++i) g[i] = uint16_t((m[i] ? 40000 : 10000) + noise(rng));
  return g;
}

std::set<uint32_t> labels_in(const Volume<uint32_t>& lab) {
  std::set<uint32_t> s;
  for (auto l : lab.span())
    if (l) s.insert(l);
  return s;
}

SegmentOptions opts(double radius) {
  SegmentOptions o;
  o.grain_radius_vox = radius;
  return o;
}

TEST(Segment, TouchingPairGivesTwoGrains) {
  auto m = Volume<uint8_t>::filled(Shape{28, 28, 46}, 0);
  draw_ball(m, 13.5, 13.5, 13.5, 10);
  draw_ball(m, 13.5, 13.5, 31.5, 10);
  const auto r = segment(grey_of(m), opts(10));
  EXPECT_EQ(r.count, 2u);
  EXPECT_EQ(r.merge.merges, 0);
  // p0 is the void fraction, so the p0-tile sits at the top of the void block (7000..13000).
  EXPECT_GT(r.threshold.value, 12500);
  EXPECT_LT(r.threshold.value, 37000);
  EXPECT_NE(r.labels(13, 13, 13), r.labels(13, 13, 31));
}

// --threshold midpoint: halfway between the void and solid peaks. Void
// 10000, solid 30000, Gaussian noise sigma 1500: the threshold comes back
// within 1 % of the contrast of 20000 (the phase modes' own error), and the
// two grains are two labels.
TEST(Segment, MidpointThresholdIsHalfwayBetweenThePhases) {
  auto m = Volume<uint8_t>::filled(Shape{28, 28, 46}, 0);
  draw_ball(m, 13.5, 13.5, 13.5, 10);
  draw_ball(m, 13.5, 13.5, 31.5, 10);
  Volume<uint16_t> g(m.shape(), m.geometry());
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 1500.0);
  for (int64_t i = 0; i < m.size(); ++i) g[i] = uint16_t(std::lround((m[i] ? 30000 : 10000) + noise(rng)));
  SegmentOptions o = opts(10);
  o.threshold = parse_threshold_method("midpoint");
  const auto r = segment(g, o);
  EXPECT_EQ(r.threshold.method, ThresholdMethod::midpoint);
  EXPECT_NEAR(r.threshold.value, 20000, 200);
  EXPECT_EQ(r.count, 2u);
}

// --threshold auto on two noisy scans of the same two balls:
// CNR 13 takes the midpoint (within 200 of 20000), CNR 4 (sigma 5000: the
// midpoint 2 sigmas above the void, under k ~ 4) keeps Tsai's level, the
// same as --threshold moments; the summary says which.
TEST(Segment, AutoThresholdTakesTheMidpointOnlyWhereTheNoiseAllows) {
  auto m = Volume<uint8_t>::filled(Shape{28, 28, 46}, 0);
  draw_ball(m, 13.5, 13.5, 13.5, 10);
  draw_ball(m, 13.5, 13.5, 31.5, 10);
  for (const double sigma : {1500.0, 5000.0}) {
    Volume<uint16_t> g(m.shape(), m.geometry());
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, sigma);
    for (int64_t i = 0; i < m.size(); ++i)
      g[i] = uint16_t(std::clamp(std::lround((m[i] ? 30000 : 10000) + noise(rng)), 0L, 65535L));
    SegmentOptions ao = opts(10);
    ao.threshold = ThresholdMethod::automatic;
    const auto r = segment(g, ao);
    EXPECT_EQ(r.threshold.method, ThresholdMethod::automatic);
    const auto js = summary_json(r, ao);
    if (sigma < 2000) {
      EXPECT_EQ(r.threshold.automatic.chosen, "midpoint");
      EXPECT_NEAR(r.threshold.value, 20000, 200);
      EXPECT_NE(js.find("\"chosen\": \"midpoint\""), std::string::npos);
    } else {
      SegmentOptions mo = opts(10);
      mo.threshold = ThresholdMethod::moments;
      EXPECT_EQ(r.threshold.automatic.chosen, "moments");
      EXPECT_EQ(r.threshold.value, segment(g, mo).threshold.value);
      EXPECT_NE(js.find("\"chosen\": \"moments\""), std::string::npos);
    }
  }
}

// The split repair's smoothing (segment.hpp kSplitSmoothingLadder): 0.7
// voxel while 6 sigmas of the noise smoothed so stay within half the
// solid's height above the threshold (white noise: sigma / 3.9 at 0.7, so
// from CNR ~6 on), 1 voxel for a noisier scan; a given sigma is kept.
TEST(Segment, SplitSmoothingFollowsTheNoiseUnlessGiven) {
  auto m = Volume<uint8_t>::filled(Shape{28, 28, 46}, 0);
  draw_ball(m, 13.5, 13.5, 13.5, 10);
  draw_ball(m, 13.5, 13.5, 31.5, 10);
  for (const double sigma : {1000.0, 6000.0}) {  // CNR 20 and 3.3 on a contrast of 20000
    Volume<uint16_t> g(m.shape(), m.geometry());
    std::mt19937 rng(12);
    std::normal_distribution<double> noise(0.0, sigma);
    for (int64_t i = 0; i < m.size(); ++i)
      g[i] = uint16_t(std::clamp(std::lround((m[i] ? 30000 : 10000) + noise(rng)), 0L, 65535L));
    const auto r = segment(g, opts(10));
    EXPECT_EQ(r.split_smoothing_vox, sigma < 2000 ? 0.7 : 1.0) << "noise sigma " << sigma;
    // The rule's own quantities: the chosen sigma's depth within half the height, or the last rung.
    const double height = 30000 - double(r.threshold.value);
    if (sigma < 2000) EXPECT_LE(6 * r.smoothed_noise_sigma, 0.5 * height);
    else EXPECT_GT(6 * r.smoothed_noise_sigma * 1.6, 0.5 * height);  // at 0.7 the noise is (1 / 0.7)^1.5 = 1.7x
    SegmentOptions given = opts(10);
    given.split_smoothing_vox = 1.5;
    const auto rg = segment(g, given);
    EXPECT_EQ(rg.split_smoothing_vox, 1.5);
    EXPECT_NE(summary_json(rg, given).find("\"smoothing_rule\": \"given\""), std::string::npos);
  }
}

TEST(Segment, SplitHalvesWithAOneVoxelGapAreTwoParticles) {
  auto m = Volume<uint8_t>::filled(Shape{32, 32, 33}, 0);
  draw_ball(m, 16, 16, 16, 13);
  test::cut_slab_x(m, 16, 1);
  const auto r = segment(grey_of(m), opts(13));
  EXPECT_EQ(r.count, 2u);
  EXPECT_EQ(r.pores.filled, 0);
  EXPECT_NE(r.labels(16, 16, 10), r.labels(16, 16, 22));
}

TEST(Segment, SphereWithInternalPoresIsOneParticle) {
  auto m = Volume<uint8_t>::filled(Shape{40, 40, 40}, 0);
  draw_ball(m, 20, 20, 20, 16);
  draw_ball(m, 20, 20, 20, 3, 0);  // pores where they hurt most: the centre
  draw_ball(m, 20, 20, 11, 2.5, 0);
  draw_ball(m, 20, 11, 20, 2.5, 0);
  draw_ball(m, 27, 24, 22, 2, 0);
  const auto r = segment(grey_of(m), opts(16));
  EXPECT_EQ(r.pores.filled, 4);
  EXPECT_EQ(r.count, 1u);
  // Without the pore filter, the central pore drives the distance map apart;
  // the label count may rise, the filter is what guarantees one label.
  EXPECT_EQ(r.labels(20, 20, 20), 1u);
}

TEST(Segment, ConstantVolumeIsAnInputError) {
  EXPECT_THROW(segment(Volume<uint16_t>::filled(Shape{8, 8, 8}, 1234), opts(5)), InputError);
}

TEST(Segment, NoiseOnlyScanIsFlagged) {
  // A scan of one noisy phase (empty specimen): any global threshold splits
  // the noise; the result carries a note saying so.
  Volume<uint16_t> g(Shape{24, 24, 24});
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(10000, 800);
  for (auto& v : g.span()) v = uint16_t(noise(rng));
  const auto r = segment(g, opts(5));
  EXPECT_LT(r.threshold.separability, 0.7);
  bool flagged = false;
  for (const auto& n : r.notes) flagged = flagged || n.find("bimodal") != std::string::npos;
  EXPECT_TRUE(flagged);
  auto m = Volume<uint8_t>::filled(Shape{28, 28, 46}, 0);
  draw_ball(m, 13.5, 13.5, 13.5, 10);
  EXPECT_GT(segment(grey_of(m), opts(10)).threshold.separability, 0.85);
}

TEST(Segment, EmptyAndAllSolidMasks) {
  auto e = segment_mask(Volume<uint8_t>::filled(Shape{8, 8, 8}, 0), opts(5));
  EXPECT_EQ(e.count, 0u);
  EXPECT_TRUE(labels_in(e.labels).empty());
  auto f = segment_mask(Volume<uint8_t>::filled(Shape{8, 8, 8}, 1), opts(5));
  EXPECT_EQ(f.count, 1u);
  for (auto l : f.labels.span()) EXPECT_EQ(l, 1u);
  EXPECT_FALSE(f.notes.empty());
}

TEST(Segment, SingleVoxelGrainsKeptWithMinSizeOne) {
  auto m = Volume<uint8_t>::filled(Shape{10, 10, 10}, 0);
  m(0, 0, 0) = m(5, 5, 5) = m(9, 2, 7) = 1;
  auto o = opts(3);
  o.min_size_vox = 1;
  auto r = segment_mask(m.clone(), o);
  EXPECT_EQ(r.count, 3u);
  o.min_size_vox = 2;
  EXPECT_EQ(segment_mask(m.clone(), o).count, 0u);
}

TEST(Segment, GrainsTouchingTheBorderStayWhole) {
  auto m = Volume<uint8_t>::filled(Shape{30, 30, 30}, 0);
  draw_ball(m, 0, 15, 15, 10);
  draw_ball(m, 22, 29, 8, 7);
  const auto r = segment(grey_of(m), opts(9));
  EXPECT_EQ(r.count, 2u);
}

TEST(Segment, AnisotropicVoxelsAndSummary) {
  auto m = Volume<uint8_t>::filled(Shape{20, 40, 40}, 0, Geometry{{20e-6, 10e-6, 10e-6}, {0, 0, 0}});
  // In physical units a ball of radius 12 fine voxels: 6 slices in z.
  for (int64_t k = 0; k < 20; ++k)
    for (int64_t j = 0; j < 40; ++j)
      for (int64_t i = 0; i < 40; ++i) {
        const double z = 2.0 * (double(k) - 9.5), y = double(j) - 19.5, x = double(i) - 19.5;
        m(k, j, i) = z * z + y * y + x * x <= 144 ? 1 : 0;
      }
  const auto r = segment(grey_of(m), opts(12));
  EXPECT_EQ(r.count, 1u);
  EXPECT_EQ(r.labels.geometry(), m.geometry());
  const auto js = summary_json(r, opts(12));
  EXPECT_NE(js.find("\"merges\""), std::string::npos);
  EXPECT_NE(js.find("\"peak_rss_bytes\""), std::string::npos);
}

TEST(Segment, ResolvedDefaultsFollowTheGrainRadius) {
  const auto o = opts(30).resolved();
  EXPECT_DOUBLE_EQ(o.h, 0.035 * 30);
  EXPECT_DOUBLE_EQ(opts(12).resolved().h, 0.5);  // the floor: above the staircase ripples
  auto given = opts(60);
  given.h = 0.5;
  EXPECT_DOUBLE_EQ(given.resolved().h, 0.5);
  EXPECT_EQ(o.pore_max_volume_vox, PoreFilterOptions::from_grain_radius(30).max_volume_vox);
  auto bad = opts(5);
  bad.connectivity = 7;
  EXPECT_THROW(bad.resolved(), UsageError);
  for (const double sigmas : {0.0, -1.0, std::nan("")}) {
    auto depth = opts(5);
    depth.split_depth_sigmas = sigmas;
    EXPECT_THROW(depth.resolved(), UsageError) << sigmas;
    depth = opts(5);
    depth.split_depth_sigmas_correlated = sigmas;
    EXPECT_THROW(depth.resolved(), UsageError) << sigmas;
  }
}

}  // namespace

// The distance map is in units of the FINEST voxel edge, so a physical grain
// radius converts with that edge (a scan whose z edge is the finest is
// common for stitched or binned stacks); with the x edge it was wrong.
TEST(Segment, GrainRadiusConvertsWithTheFinestEdge) {
  Geometry g;
  g.voxel_size_m = {5e-6, 10e-6, 20e-6};  // z finest
  EXPECT_DOUBLE_EQ(grain_radius_in_voxels(100e-6, g), 20.0);
  g.voxel_size_m = {12e-6, 12e-6, 6e-6};  // x finest
  EXPECT_DOUBLE_EQ(grain_radius_in_voxels(120e-6, g), 20.0);
  EXPECT_THROW(grain_radius_in_voxels(1e-4, Geometry{}), UsageError);
}
}  // namespace tg

// Grains of different brightness: the scan levelled grain by grain before
// the threshold (segmentation/grain_levels.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "scan_scenes.hpp"
#include "segmentation/grain_levels.hpp"
#include "segmentation/segment.hpp"

namespace tg {
namespace {

constexpr double kV = 10000, kP = 30000;

// Noiseless blocks, analytic answers: a block at half the solid's contrast
// is raised to the solid's level where the smoothing and the maximum read it
// alone (gain 2 >= smooth_from_gain: from the smoothed grey, which is the
// block's own level there); a block at the solid's level and the void far
// from both are copied as they are.
TEST(GrainLevels, ABlockAtHalfTheContrastIsRaisedToTheSolidAndTheRestLeftAlone) {
  const int64_t n = 48;
  Volume<uint16_t> g = Volume<uint16_t>::filled(Shape{n, n, n}, uint16_t(kV));
  auto block = [&](int64_t z0, uint16_t v) {
    for (int64_t k = z0; k < z0 + 14; ++k)
      for (int64_t j = 17; j < 31; ++j)
        for (int64_t i = 17; i < 31; ++i) g(k, j, i) = v;
  };
  block(4, uint16_t(0.5 * (kV + kP)));  // dim: slices 4..17
  block(30, uint16_t(kP));              // bright: slices 30..43
  GrainLevelsResult res;
  const Volume<uint16_t> out = normalise_grain_levels(g, {kV, kP, 100.0}, GrainLevelsOptions{}, &res);
  ASSERT_TRUE(res.used);
  for (int64_t k = 0; k < n; ++k)
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i) {
        const bool dim_core = k >= 8 && k <= 13 && j >= 21 && j <= 26 && i >= 21 && i <= 26;  // 4 voxels inside
        const bool far = j < 17 - 8 || j > 30 + 8 || i < 17 - 8 || i > 30 + 8;  // past smoothing + reach
        if (dim_core) {
          ASSERT_NEAR(double(out(k, j, i)), kP, 1.0) << k << " " << j << " " << i;
        } else if (far || g(k, j, i) == uint16_t(kP)) {
          ASSERT_EQ(out(k, j, i), g(k, j, i)) << k << " " << j << " " << i;
        }
      }
  // Every voxel raised lies within reach + smoothing of a block: the dim
  // one, and the bright one's blurred surroundings.
  EXPECT_GT(res.voxels_raised, 14 * 14 * 14);
  EXPECT_LT(res.voxels_raised, 2 * 26 * 26 * 26);
}

// 64 balls of radius 9, 3 voxels apart, a third each at 0.35, 0.6 and 1 of
// the solid's contrast over the void, every fifth cut by an oblique 1-voxel
// gap; PSF 0.7, CNR 13 (of the full contrast: the dimmest balls stand 4.5
// noise sigmas above the void). Truth: the balls' and halves' voxels.
test::BrightnessScene three_brightnesses(uint64_t seed) {
  return test::grid_of_balls(
      4, 21, 9, [](int b) { return b % 5 == 0; },
      [](int b) { return std::array<double, 3>{0.35, 0.6, 1.0}[size_t(b % 3)]; }, seed);
}

struct Recovered {
  int whole = 0;                 // truth particles with a label of IoU > 0.7
  double median_dv = 1.0;        // median |dV/V| of the labels matched
};

Recovered recovered(const test::BrightnessScene& s, const SegmentResult& r, uint32_t nt) {
  // Overlaps by pairs (one pass), then each truth's best label by IoU.
  std::map<std::pair<uint32_t, uint32_t>, int64_t> both;
  std::map<uint32_t, int64_t> ts, ls;
  for (int64_t q = 0; q < s.truth.size(); ++q) {
    const uint32_t t = s.truth.data()[q], l = r.labels.data()[q];
    if (t) ++ts[t];
    if (l) ++ls[l];
    if (t && l) ++both[{t, l}];
  }
  std::map<uint32_t, std::pair<double, uint32_t>> best;
  for (const auto& [tl, c] : both) {
    const double iou = double(c) / double(ts[tl.first] + ls[tl.second] - c);
    if (iou > best[tl.first].first) best[tl.first] = {iou, tl.second};
  }
  Recovered out;
  std::vector<double> dv;
  for (uint32_t t = 1; t <= nt; ++t) {
    const auto it = best.find(t);
    if (it == best.end() || it->second.first <= 0.7) continue;
    ++out.whole;
    dv.push_back(std::abs(double(ls[it->second.second]) / double(ts[t]) - 1.0));
  }
  if (!dv.empty()) {
    std::nth_element(dv.begin(), dv.begin() + long(dv.size() / 2), dv.end());
    out.median_dv = dv[dv.size() / 2];
  }
  return out;
}

// The dim balls lie under any global threshold the noise allows: without the
// levelling most of them are lost or come out as specks; with it every ball
// and half comes out whole, at its own half contrast (volumes within a few
// per cent). Seed 1 was looked at while writing this (77 of 77 whole, 50
// without; median |dV/V| 0.021 against 0.097); the assertions run on seeds
// 2-3 (the same counts, 0.022-0.023 against 0.100).
TEST(GrainLevels, DimGrainsComeOutWholeAtHalfTheirOwnContrast) {
  for (uint64_t seed : {2u, 3u}) {
    const auto s = three_brightnesses(seed);
    const uint32_t nt = 64 + 13;
    SegmentOptions o;
    o.grain_radius_vox = 9;
    const SegmentResult r = segment(s.grey, o);
    o.grain_levels = false;
    const SegmentResult off = segment(s.grey, o);
    const Recovered a = recovered(s, r, nt), b = recovered(s, off, nt);
    const std::string what = "seed " + std::to_string(seed) + ": whole " + std::to_string(a.whole) + " of " +
                             std::to_string(nt) + " (" + std::to_string(b.whole) + " without), median |dV/V| " +
                             std::to_string(a.median_dv) + " (" + std::to_string(b.median_dv) +
                             "), spread ratio " + std::to_string(r.grain_levels.spread_ratio) + ", pairs " + std::to_string(r.within_grain_pairs);
    EXPECT_TRUE(r.grain_levels.used) << what;
    EXPECT_GE(r.grain_levels.spread_ratio, GrainLevelsOptions{}.min_spread_ratio) << what;
    EXPECT_FALSE(off.grain_levels.used) << what;
    EXPECT_EQ(a.whole, int(nt)) << what;
    EXPECT_LT(a.median_dv, 0.05) << what;
    EXPECT_LE(b.whole, int(nt) - 8) << what;  // the scene needs it
  }
}

// The dim-population detector on histograms made by hand: the void's and
// the solid's Gaussian peaks with the partial volume between them falling
// from the void and rising to the solid (grains of one brightness: no
// interior maximum), with a Gaussian population at 0.45 of the contrast
// added (found, at its level), and a broad bump that cupping leaves beside
// the solid peak (not found).
std::vector<int64_t> two_phase_histogram(double dim_share, double bump_share) {
  std::vector<int64_t> h(65536, 0);
  const double V = 10000, P = 30000, sv = 250, sp = 250;
  for (int g = 0; g < 65536; ++g) {
    const double x = g;
    double f = 4e5 * std::exp(-0.5 * std::pow((x - V) / sv, 2)) + 6e5 * std::exp(-0.5 * std::pow((x - P) / sp, 2));
    if (x > V && x < P) {
      const double u = (x - V) / (P - V);  // partial volume: more near either phase
      f += 300.0 * (1.0 + 3.0 * (std::pow(1 - u, 4) + std::pow(u, 4)));
    }
    f += dim_share * 6e5 * std::exp(-0.5 * std::pow((x - (V + 0.45 * (P - V))) / 300.0, 2));
    f += bump_share * 6e5 * std::exp(-0.5 * std::pow((x - (V + 0.8 * (P - V))) / 3000.0, 2));
    h[size_t(g)] = int64_t(std::llround(f));
  }
  return h;
}

TEST(GrainLevels, APopulationOfDarkerGrainsIsAPeakBetweenThePhases) {
  const GrainLevelsInput in{10000, 30000, 250};
  const DimPopulation none = dim_population(two_phase_histogram(0.0, 0.0), in);
  EXPECT_FALSE(none.found) << none.prominence;
  for (const double share : {0.05, 0.2, 0.5}) {
    const DimPopulation d = dim_population(two_phase_histogram(share, 0.0), in);
    EXPECT_TRUE(d.found) << share << ": prominence " << d.prominence;
    EXPECT_NEAR(d.level, 19000, 500) << share;
  }
  // A broad shoulder below the solid peak (brightness falling off toward
  // the scan's middle; blind scenes with cupping 0.3 measured prominence
  // 1.2) is no population apart: its floor toward the solid is high.
  const DimPopulation bump = dim_population(two_phase_histogram(0.0, 0.05), in);
  EXPECT_FALSE(bump.found) << bump.prominence;
}

// Grains of one brightness: the solid peak is as wide as the noise inside a
// grain, so the scan is not levelled (it would raise the partial volume of
// crumbs at the faces and of blurred chips, and grow them).
TEST(GrainLevels, GrainsOfOneBrightnessAreLeftAlone) {
  const auto s = test::grid_of_balls(
      4, 21, 9, [](int b) { return b % 5 == 0; }, [](int) { return 1.0; }, 2);
  SegmentOptions o;
  o.grain_radius_vox = 9;
  const SegmentResult r = segment(s.grey, o);
  EXPECT_FALSE(r.grain_levels.used);
  EXPECT_FALSE(r.grain_levels.dim.found) << r.grain_levels.dim.prominence;
  EXPECT_GT(r.grain_levels.spread_ratio, 0.5);
  EXPECT_LT(r.grain_levels.spread_ratio, 1.5);
}

}  // namespace
}  // namespace tg

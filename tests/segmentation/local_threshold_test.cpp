// Uneven brightness (issue 19, item 4): the windowed moments threshold on
// stand-ins with cupping and with a gradient along z. Scenes: scan_scenes.hpp
// (balls R 6, 35 % solid, void 10000 / solid 30000, blur sigma 1 voxel,
// noise 1500). Scene, window and tolerances were set on seeds 21 and 22
// (measured in the comments); the assertions run on 31 and 32.
#include "segmentation/local_threshold.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "core/errors.hpp"
#include "scan_scenes.hpp"
#include "segmentation/segment.hpp"

namespace tg {
namespace {

double fraction(const Volume<uint8_t>& m) {
  int64_t s = 0;
  for (auto v : m.span()) s += v != 0;
  return double(s) / double(m.size());
}

constexpr double kBlur = 0.7, kRadius = 8;

struct Fractions {
  double truth, even, global, local;  // even: the global threshold on the same scan without the brightness field
};

Fractions run(const test::Offset& offset, unsigned seed, int64_t window) {
  const Shape s{64, 128, 128};
  const auto truth = test::ball_packing(s, kRadius, 0.35, seed);
  SegmentOptions o;
  o.grain_radius_vox = kRadius;
  const double even = offset ? segment(test::image(truth, kBlur, nullptr, seed), o).solid_fraction : 0.0;
  const auto g = test::image(truth, kBlur, offset, seed);
  const auto rg = segment(g, o);
  o.threshold = ThresholdMethod::local;
  o.local_window_vox = window;
  const auto rl = segment(g, o);
  EXPECT_EQ(rl.threshold.method, ThresholdMethod::local);
  EXPECT_GT(rl.local.trusted, 0);
  if (window == 0) {
    EXPECT_EQ(rl.local.window, 32);  // the default, 4 R
  }
  return {fraction(truth), offset ? even : rg.solid_fraction, rg.solid_fraction, rl.solid_fraction};
}

// Both stand-ins: 64 x 128 x 128, balls R 8, window 32 voxels (the default, 4 R).
// Tsai's threshold itself overestimates the solid of this blurred scene by
// ~1.7 % at even brightness (its p0-tile sits at the top of the void peak,
// into the partial-volume voxels); the brightness field's own error is the
// difference to that even-brightness answer, asserted within 0.7 %; the
// local threshold is within 2.5 % of the truth where the global one is off
// by 4 % or more.

// The local threshold recovers the solid fraction under `shade` (within
// 2.5 % of the truth and 0.7 % of the evenly lit scan) where the global one
// misses it by more than 3.5 % (the stand-in shows the failure).
void expect_local_recovers(const char* what, const test::Offset& shade,
                           unsigned seed) {
  const Fractions r = run(shade, seed, 0);
  std::printf("%s seed %u: truth %.4f even %.4f global %.4f local %.4f\n", what, seed, r.truth, r.even, r.global,
              r.local);
  EXPECT_NEAR(r.local / r.truth, 1.0, 0.025);
  EXPECT_NEAR(r.local / r.even, 1.0, 0.007);
  EXPECT_GT(std::abs(r.global / r.truth - 1.0), 0.035) << "the stand-in must show the failure";
}

// Cupping: both phases darker towards the axis, by 30 % of the contrast
// (6000 of 20000) at the axis, quadratic in the radius, 0 at the slice's
// inscribed circle.
// Measured, solid fraction (truth / even / global / local):
//   seed 21:            0.3512 / 0.3573 / 0.3666 (+4.4 %) / 0.3576 (+1.8 %)
//   seed 22:            0.3503 / 0.3564 / 0.3644 (+4.0 %) / 0.3571 (+1.9 %)
//   seed 31 (asserted): 0.3502 / 0.3563 / 0.3644 (+4.1 %) / 0.3567 (+1.9 %)
TEST(LocalThreshold, CuppingRecoversTheSolidFraction) {
  expect_local_recovers("cupping", [](int64_t, int64_t j, int64_t i) {
    const double r2 = (std::pow(double(j) - 63.5, 2) + std::pow(double(i) - 63.5, 2)) / (64.0 * 64.0);
    return -6000.0 * std::max(0.0, 1.0 - r2);
  }, 31);
}

// A linear drift along z, both phases: -3000 at the first slice to +3000
// at the last (30 % of the contrast end to end).
// Measured, solid fraction (truth / even / global / local):
//   seed 21:            0.3512 / 0.3573 / 0.3648 (+3.9 %) / 0.3592 (+2.3 %)
//   seed 22:            0.3503 / 0.3564 / 0.3656 (+4.4 %) / 0.3579 (+2.2 %)
//   seed 32 (asserted): 0.3518 / 0.3578 / 0.3682 (+4.7 %) / 0.3597 (+2.2 %)
TEST(LocalThreshold, GradientAlongZRecoversTheSolidFraction) {
  expect_local_recovers("drift", [](int64_t k, int64_t, int64_t) { return 3000.0 * (2.0 * double(k) / 63.0 - 1.0); },
                        32);
}

// Even brightness: the local threshold is the global one, within a bin and the noise.
TEST(LocalThreshold, EvenBrightnessAgreesWithTheGlobalThreshold) {
  const Fractions r = run(nullptr, 31, 0);
  std::printf("even: truth %.4f global %.4f local %.4f\n", r.truth, r.global, r.local);
  EXPECT_NEAR(r.local, r.global, 0.005);
}

// Blocks that are not bimodal (all void above the packing) take their
// neighbours' threshold; a volume with no bimodal block falls back to the
// global threshold with a note.
TEST(LocalThreshold, UnimodalBlocksTakeTheirNeighboursValue) {
  const Shape s{48, 48, 48};
  auto truth = test::ball_packing(s, 4, 0.35, 21);
  for (int64_t k = 24; k < 48; ++k)
    for (int64_t j = 0; j < 48; ++j)
      for (int64_t i = 0; i < 48; ++i) truth(k, j, i) = 0;  // void above z = 24
  const auto g = test::image(truth, 0, nullptr, 21);
  auto hist = histogram_u16(g);
  const auto lt = local_moments_thresholds(g, {}, hist, 16, 20000);
  EXPECT_EQ(lt.nbz * lt.nby * lt.nbx, 27);
  EXPECT_EQ(lt.trusted + lt.filled, 27);
  EXPECT_GE(lt.filled, 9);  // the top layer at least
  EXPECT_GT(lt.min, 12000);
  EXPECT_LT(lt.max, 28000);
  const auto mask = binarise_local(g, lt, {});
  int64_t top = 0;
  for (int64_t k = 32; k < 48; ++k)
    for (int64_t j = 0; j < 48; ++j)
      for (int64_t i = 0; i < 48; ++i) top += mask(k, j, i);
  // The void layer stays void but for the noise's tail above the filled
  // thresholds (Tsai's t sits at the top of the void peak, ~10000 + 2.3 sigma).
  EXPECT_LT(double(top), 0.02 * 16 * 48 * 48);
  // Noise only: no block is bimodal.
  const auto n = test::image(Volume<uint8_t>::filled(s, 0), 0, nullptr, 22);
  auto hn = histogram_u16(n);
  const auto ln = local_moments_thresholds(n, {}, hn, 16, 12345);
  EXPECT_EQ(ln.trusted, 0);
  EXPECT_FALSE(ln.note.empty());
  EXPECT_FLOAT_EQ(ln.min, 12345.f);
}

// The in-place mask (rvalue scan) equals the copying one; anisotropic shape,
// a field of view, a window larger than an axis.
TEST(LocalThreshold, InPlaceEqualsCopyAndHonoursTheFieldOfView) {
  const Shape s{10, 50, 70};
  const auto g = test::image(test::ball_packing(s, 4, 0.35, 22), 0.7, nullptr, 22);
  const auto fov = circular_field_of_view(24.5, 34.5, 22, s);
  auto hist = histogram_in_fov(g, fov);
  const auto lt = local_moments_thresholds(g, fov, hist, 24, 20000);
  EXPECT_EQ(lt.nbz, 1);
  EXPECT_EQ(lt.nby, 2);
  EXPECT_EQ(lt.nbx, 3);
  const auto a = binarise_local(g, lt, fov);
  auto copy = g.clone();
  const auto b = binarise_local(std::move(copy), lt, fov);
  ASSERT_EQ(a.shape(), b.shape());
  for (int64_t q = 0; q < a.size(); ++q) ASSERT_EQ(a[q], b[q]) << q;
  EXPECT_EQ(a(5, 0, 0), 0);
  EXPECT_EQ(a(5, 49, 69), 0);
  EXPECT_THROW(local_moments_thresholds(g, fov, hist, 1, 20000), UsageError);
}

}  // namespace
}  // namespace tg

#include "segmentation/normalise.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/errors.hpp"

namespace tg {
namespace {

TEST(Normalise, LinearMapWithClipping) {
  Volume<float> v(Shape{1, 1, 6});
  const float x[] = {-5.f, 0.f, 2.5f, 5.f, 10.f, 20.f};
  std::copy(x, x + 6, v.begin());
  auto u = normalise_to_u16(v, {0.0, 10.0, "test"});
  EXPECT_EQ(u[0], 0);                                    // below lo: clipped
  EXPECT_EQ(u[1], 0);                                    // lo -> 0
  EXPECT_EQ(u[2], static_cast<uint16_t>(std::lround(65535 * 0.25)));  // 16383.75 -> 16384
  EXPECT_EQ(u[3], 32768);                                // 32767.5 rounds up
  EXPECT_EQ(u[4], 65535);                                // hi -> 65535
  EXPECT_EQ(u[5], 65535);                                // above hi: clipped
}

TEST(Normalise, KeepsGeometry) {
  auto v = Volume<float>::filled(Shape{2, 3, 4}, 1.f, Geometry::isotropic_m(12.3e-6));
  auto u = normalise_to_u16(v, {0.0, 2.0, ""});
  EXPECT_EQ(u.shape(), v.shape());
  EXPECT_EQ(u.geometry(), v.geometry());
  EXPECT_EQ(u[0], 32768);
}

TEST(Normalise, RejectsBadRange) {
  auto v = Volume<float>::filled(Shape{1, 1, 2}, 1.f);
  EXPECT_THROW(normalise_to_u16(v, {1.0, 1.0, ""}), UsageError);
  EXPECT_THROW(normalise_to_u16(v, {2.0, 1.0, ""}), UsageError);
  EXPECT_THROW(normalise_to_u16(v, {0.0, std::numeric_limits<double>::infinity(), ""}), UsageError);
}

TEST(Normalise, NanMapsToZero) {
  auto v = Volume<float>::filled(Shape{1, 1, 1}, std::numeric_limits<float>::quiet_NaN());
  EXPECT_EQ(normalise_to_u16(v, {0.0, 1.0, ""})[0], 0);
}

// Uniform ramp 0..N-1: the q-percentile of the values is q*N (histogram
// interpolation is exact for a uniform density up to one 2^-20 bin).
TEST(NormaliseAutoRange, PercentilesOfRamp) {
  const int64_t n = 1'000'000;
  Volume<float> v(Shape{1, 1000, 1000});
  for (int64_t i = 0; i < n; ++i) v[i] = float(i);
  const auto r = auto_range(v);
  const double tol = double(n) / double(1 << 20) + 1.0;
  EXPECT_NEAR(r.lo, 1e-4 * n, tol);
  EXPECT_NEAR(r.hi, 0.9999 * n, tol);
  EXPECT_FALSE(r.how.empty());
}

// Outliers (0.005 % of the voxels, beyond the 0.01 % tails) do not move the range.
TEST(NormaliseAutoRange, IgnoresRareOutliers) {
  Volume<float> v(Shape{10, 100, 200});  // 200 000 voxels
  for (int64_t i = 0; i < v.size(); ++i) v[i] = (i % 2) ? 1.0f : 2.0f;
  for (int64_t i = 0; i < 5; ++i) v[i * 1000] = 1e6f;
  for (int64_t i = 0; i < 5; ++i) v[i * 1000 + 1] = -1e6f;
  const auto r = auto_range(v);
  EXPECT_NEAR(r.lo, 1.0, 2e6 / double(1 << 20) + 1e-9);
  EXPECT_NEAR(r.hi, 2.0, 2e6 / double(1 << 20) + 1e-9);
}

TEST(NormaliseAutoRange, DegenerateInputs) {
  EXPECT_THROW(auto_range(Volume<float>(Shape{0, 0, 0})), InputError);
  EXPECT_THROW(auto_range(Volume<float>::filled(Shape{2, 2, 2}, 3.f)), InputError);
  EXPECT_THROW(auto_range(Volume<float>::filled(Shape{2, 2, 2}, std::numeric_limits<float>::quiet_NaN())),
               InputError);
}

}  // namespace
}  // namespace tg

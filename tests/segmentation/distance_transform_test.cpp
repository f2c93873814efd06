#include "segmentation/distance_transform.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/errors.hpp"

namespace tg {
namespace {

// Brute force: for every voxel, the minimum over all void voxels of the
// squared anisotropic distance between centres. O(N^2), small volumes only.
std::vector<double> brute_sq(const Volume<uint8_t>& m, std::array<double, 3> w) {
  const Shape s = m.shape();
  std::vector<std::array<int64_t, 3>> voids;
  for (int64_t i = 0; i < m.size(); ++i)
    if (m[i] == 0) voids.push_back(s.coords(i));
  std::vector<double> d(size_t(m.size()), std::numeric_limits<double>::infinity());
  for (int64_t i = 0; i < m.size(); ++i) {
    const auto c = s.coords(i);
    for (const auto& v : voids) {
      const double a = w[0] * double(c[0] - v[0]), b = w[1] * double(c[1] - v[1]), e = w[2] * double(c[2] - v[2]);
      d[size_t(i)] = std::min(d[size_t(i)], a * a + b * b + e * e);
    }
  }
  return d;
}

Volume<uint8_t> random_mask(Shape s, double p_void, unsigned seed) {
  Volume<uint8_t> m(s);
  std::mt19937 rng(seed);
  std::bernoulli_distribution b(p_void);
  for (auto& v : m.span()) v = b(rng) ? 0 : 1;
  return m;
}

void expect_matches_brute(const Volume<uint8_t>& m, std::array<double, 3> w) {
  Volume<float> d;
  squared_distance_transform(m, d, {w});
  const auto want = brute_sq(m, w);
  for (int64_t i = 0; i < m.size(); ++i) {
    if (std::isinf(want[size_t(i)])) {
      ASSERT_TRUE(std::isinf(d[i]));
      continue;
    }
    // Float storage between passes: relative 1e-6 (plus an absolute floor).
    ASSERT_NEAR(d[i], want[size_t(i)], 1e-6 * want[size_t(i)] + 1e-9) << "voxel " << i;
  }
}

TEST(DistanceTransform, MatchesBruteForceIsotropic) {
  unsigned seed = 1;
  for (double p : {0.002, 0.01, 0.05, 0.3})
    expect_matches_brute(random_mask(Shape{14, 15, 33}, p, seed++), {1, 1, 1});
}

TEST(DistanceTransform, MatchesBruteForceAnisotropic) {
  unsigned seed = 10;
  for (auto w : {std::array<double, 3>{2.5, 1.0, 1.0}, {1.0, 0.7, 3.0}, {0.3, 5.0, 1.1}})
    for (double p : {0.005, 0.05}) expect_matches_brute(random_mask(Shape{11, 19, 21}, p, seed++), w);
}

TEST(DistanceTransform, SingleVoidVoxelAndBorders) {
  auto m = Volume<uint8_t>::filled(Shape{9, 10, 11}, 1);
  m(0, 0, 0) = 0;  // distances grow from the corner; the border is not void
  Volume<float> d;
  distance_transform(m, d, {{2.0, 1.0, 1.0}});
  EXPECT_FLOAT_EQ(d(8, 9, 10), float(std::sqrt(16.0 * 16 + 81 + 100)));
  EXPECT_FLOAT_EQ(d(0, 0, 0), 0.f);
  EXPECT_FLOAT_EQ(d(0, 0, 3), 3.f);
}

TEST(DistanceTransform, AllSolidIsInfiniteAllVoidIsZero) {
  Volume<float> d;
  distance_transform(Volume<uint8_t>::filled(Shape{4, 5, 6}, 1), d);
  for (float v : d.span()) EXPECT_TRUE(std::isinf(v));
  distance_transform(Volume<uint8_t>::filled(Shape{4, 5, 6}, 0), d);
  for (float v : d.span()) EXPECT_EQ(v, 0.f);
  distance_transform(Volume<uint8_t>(Shape{0, 0, 0}), d);
  EXPECT_TRUE(d.empty());
}

TEST(DistanceTransform, BallCentreDepth) {
  // Solid ball of radius 10 in void: the centre voxel is ~10 from the nearest void.
  const Shape s{25, 25, 25};
  Volume<uint8_t> m(s);
  for (int64_t k = 0; k < 25; ++k)
    for (int64_t j = 0; j < 25; ++j)
      for (int64_t i = 0; i < 25; ++i)
        m(k, j, i) = (k - 12) * (k - 12) + (j - 12) * (j - 12) + (i - 12) * (i - 12) <= 100 ? 1 : 0;
  Volume<float> d;
  distance_transform(m, d);
  // The nearest lattice point outside the ball has |x|^2 = 101, e.g. (10, 1, 0).
  EXPECT_NEAR(d(12, 12, 12), std::sqrt(101.0), 1e-5);
}

TEST(DistanceTransform, LineKernelAgainstDefinition) {
  const float inf = std::numeric_limits<float>::infinity();
  const float f[] = {inf, 4.f, inf, inf, 0.f, inf, 9.f};
  float d[7];
  int64_t v[7];
  double z[8];
  detail::edt_line(f, 7, 1.5, d, v, z);
  for (int p = 0; p < 7; ++p) {
    double best = std::numeric_limits<double>::infinity();
    for (int q = 0; q < 7; ++q)
      if (!std::isinf(f[q])) best = std::min(best, 2.25 * (p - q) * (p - q) + f[q]);
    EXPECT_NEAR(d[p], best, 1e-5);
  }
}

TEST(DistanceTransform, RejectsBadSpacing) {
  Volume<float> d;
  EXPECT_THROW(distance_transform(Volume<uint8_t>::filled(Shape{1, 1, 1}, 1), d, {{0.0, 1.0, 1.0}}), UsageError);
}

}  // namespace
}  // namespace tg

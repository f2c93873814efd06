#include "segmentation/distance_transform.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

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

// The line kernel against its definition, min over finite f[q] of
// (w (p - q))^2 + f[q], on lines with +inf samples (rows without void),
// zeros cutting the line, none at all, or only +inf; read and written at a
// stride, in place, as passes y and z use it.
void expect_line_matches_definition(const std::vector<float>& f, double w) {
  const int64_t n = int64_t(f.size()), stride = 3;
  std::vector<float> buf(size_t(n * stride), -1.f);
  for (int64_t p = 0; p < n; ++p) buf[size_t(p * stride)] = f[size_t(p)];
  std::vector<detail::EnvelopeSite> sites(size_t(n + 1));
  detail::edt_line(buf.data(), buf.data(), n, stride, w, sites.data());
  for (int64_t p = 0; p < n; ++p) {
    double best = std::numeric_limits<double>::infinity();
    for (int64_t q = 0; q < n; ++q)
      if (!std::isinf(f[size_t(q)])) best = std::min(best, w * w * double((p - q) * (p - q)) + f[size_t(q)]);
    const float got = buf[size_t(p * stride)];
    if (std::isinf(best)) {
      ASSERT_TRUE(std::isinf(got)) << "p " << p;
    } else {
      ASSERT_NEAR(got, best, 1e-6 * best + 1e-9) << "p " << p;
    }
    ASSERT_EQ(buf[size_t(p * stride + 1)], -1.f);  // the neighbouring column is untouched
  }
}

TEST(DistanceTransform, LineKernelAgainstDefinition) {
  const float inf = std::numeric_limits<float>::infinity();
  expect_line_matches_definition({inf, 4.f, inf, inf, 0.f, inf, 9.f}, 1.5);
  expect_line_matches_definition({inf, inf, inf}, 1.0);              // no finite site: +inf
  expect_line_matches_definition({inf, inf, 7.f, inf, inf}, 0.5);    // one finite site, no zero
  expect_line_matches_definition({0.f, 0.f, 3.f, 0.f, 0.f}, 2.0);    // zeros next to zeros
  expect_line_matches_definition({5.f}, 1.0);
  // Random lines: zeros, +inf and finite values of pass-x-like size.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> kind(0, 9), val(1, 400);
  for (double w : {1.0, 0.5, 3.0})
    for (int t = 0; t < 200; ++t) {
      std::vector<float> f(size_t(1 + t % 60));
      const int p_zero = t % 4, p_inf = (t / 4) % 4;  // from none to many
      for (auto& x : f) {
        const int c = kind(rng);
        x = c < p_zero ? 0.f : c < p_zero + p_inf ? inf : float(val(rng));
      }
      expect_line_matches_definition(f, w);
    }
}

TEST(DistanceTransform, SolidRowsAndBorderRuns) {
  // Rows and whole slices with no void (+inf after pass x) inside a mixed
  // volume, and solid runs that touch the volume border in every direction.
  auto m = Volume<uint8_t>::filled(Shape{12, 13, 17}, 1);
  m(3, 4, 5) = 0, m(3, 4, 6) = 0, m(9, 11, 1) = 0, m(0, 12, 16) = 0;
  expect_matches_brute(m, {1, 1, 1});
  expect_matches_brute(m, {3, 1, 0.5});  // strong anisotropy
  for (int64_t j = 0; j < 13; ++j)       // a void plane: runs on both sides end at the border
    for (int64_t i = 0; i < 17; ++i) m(6, j, i) = 0;
  expect_matches_brute(m, {0.5, 3, 1});
}

TEST(DistanceTransform, MatchesBruteForceStrongAnisotropy) {
  unsigned seed = 40;
  for (auto w : {std::array<double, 3>{3.0, 1.0, 0.5}, {0.5, 1.0, 3.0}, {1.0, 7.0, 0.2}})
    for (double p : {0.003, 0.02, 0.2}) expect_matches_brute(random_mask(Shape{13, 17, 23}, p, seed++), w);
}

TEST(DistanceTransform, DistanceIsRootOfSquaredAndThinVolumes) {
  // distance_transform takes the root in its last pass: in pass z, or in
  // pass y for a single slice.
  for (Shape s : {Shape{9, 10, 37}, Shape{1, 10, 37}, Shape{5, 1, 1}, Shape{1, 1, 20}}) {
    const auto m = random_mask(s, 0.05, 3);
    Volume<float> sq, d;
    squared_distance_transform(m, sq, {{1.0, 2.0, 0.7}});
    distance_transform(m, d, {{1.0, 2.0, 0.7}});
    for (int64_t i = 0; i < m.size(); ++i) ASSERT_EQ(d[i], std::sqrt(sq[i])) << s.str() << " voxel " << i;
    expect_matches_brute(m, {1.0, 2.0, 0.7});
  }
}

// The windowed kernel of passes y and z against the definition, line by
// line of a block: zeros, +inf and finite values, windows reaching the line
// ends, anisotropic spacing; and its refusal when windows would be wide.
TEST(DistanceTransform, BlockWindowAgainstDefinition) {
  const float inf = std::numeric_limits<float>::infinity();
  constexpr int64_t B = detail::kEdtBlock;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> kind(0, 9), val(1, 60);
  for (double w : {1.0, 0.5, 3.0, 0.7})
    for (int64_t n : {1, 2, 7, 40, 130}) {
      std::vector<float> in(size_t(n * B)), out(size_t(n * B), -1.f), cost(static_cast<size_t>(n));
      std::vector<int64_t> radius(static_cast<size_t>(n));
      for (auto& x : in) {
        const int c = kind(rng);
        x = c < 3 ? 0.f : c < 4 && n < 50 ? inf : float(val(rng)) * float(w * w);
      }
      // Finite values up to 60 w^2: windows of radius 7 at most, accepted.
      ASSERT_TRUE(detail::edt_block_window(in.data(), out.data(), n, B, w, radius.data(), cost.data()));
      for (int64_t b = 0; b < B; ++b)
        for (int64_t p = 0; p < n; ++p) {
          double best = std::numeric_limits<double>::infinity();
          for (int64_t q = 0; q < n; ++q)
            best = std::min(best, w * w * double((p - q) * (p - q)) + in[size_t(q * B + b)]);
          const float got = out[size_t(p * B + b)];
          if (std::isinf(best)) {
            ASSERT_TRUE(std::isinf(got));
          } else {
            // float arithmetic: two roundings at most
            ASSERT_NEAR(got, best, 3e-7 * best) << "w " << w << " n " << n << " line " << b << " p " << p;
          }
        }
    }
  // A block with a +inf row on a long line (no void anywhere along it) is
  // refused: its window would be the whole line at every row.
  const int64_t n = 300;
  std::vector<float> in(size_t(n * B), 1.f), out(size_t(n * B), -1.f), cost(static_cast<size_t>(n));
  std::vector<int64_t> radius(static_cast<size_t>(n));
  for (int64_t b = 0; b < B; ++b) in[size_t(b)] = 0.f;
  for (int64_t p = 0; p < n; ++p) in[size_t(p * B + 5)] = inf;
  EXPECT_FALSE(detail::edt_block_window(in.data(), out.data(), n, B, 1.0, radius.data(), cost.data()));
  for (float x : out) ASSERT_EQ(x, -1.f);  // refused: nothing written
  for (int64_t p = 1; p < n; ++p) in[size_t(p * B + 5)] = 1.f;  // the line has a void again
  in[size_t(5)] = 0.f;
  ASSERT_TRUE(detail::edt_block_window(in.data(), out.data(), n, B, 1.0, radius.data(), cost.data()));
  EXPECT_EQ(out[size_t(5)], 0.f);
  EXPECT_EQ(out[size_t(7 * B + 5)], 1.f);
}

TEST(DistanceTransform, LongLinesMixWindowsAndEnvelopes) {
  // Lines along z of 230 voxels: blocks with sparse voids or none along a
  // line take the envelopes, blocks in the dense half the windows; a partial
  // block of 2 lines at the end of each row.
  Volume<uint8_t> m = random_mask(Shape{230, 5, 18}, 0.0015, 21);
  for (int64_t k = 0; k < 60; ++k)
    for (int64_t j = 0; j < 5; ++j)
      for (int64_t i = 0; i < 18; ++i)
        if ((k * 7 + j * 3 + i) % 5 == 0) m(k, j, i) = 0;
  expect_matches_brute(m, {1, 1, 1});
  expect_matches_brute(m, {0.5, 1, 3});
}

TEST(DistanceTransform, RejectsBadSpacing) {
  Volume<float> d;
  EXPECT_THROW(distance_transform(Volume<uint8_t>::filled(Shape{1, 1, 1}, 1), d, {{0.0, 1.0, 1.0}}), UsageError);
}

}  // namespace
}  // namespace tg

// Ring removal (segmentation/rings.hpp) on constructed slices: a grey that
// varies smoothly with the radius (as a packing's mean does) plus Gaussian
// noise, with and without rings at known radii.
#include "segmentation/rings.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <omp.h>

#include "core/errors.hpp"

namespace tg {
namespace {

// 24 slices of 64 x 64 about the slice's centre (32, 32); bin b = the
// floor of a voxel centre's distance. Grey 12000 + 80 b + noise sigma 1500
// (outside radius 30: 0, a pre-masked field of view), plus `rings` offsets.
Volume<float> slices(const std::vector<std::pair<int, double>>& rings, uint64_t seed, double cy = 32, double cx = 32) {
  Volume<float> v(Shape{24, 64, 64});
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, 1500);
  for (int64_t k = 0; k < 24; ++k)
    for (int64_t j = 0; j < 64; ++j)
      for (int64_t i = 0; i < 64; ++i) {
        const int b = int(std::floor(std::hypot(double(j) + 0.5 - 32, double(i) + 0.5 - 32)));
        const int c = int(std::floor(std::hypot(double(j) + 0.5 - cy, double(i) + 0.5 - cx)));  // the rings' bin
        double g = b > 30 ? 0.0 : 12000 + 80.0 * b + noise(rng);
        for (const auto& [rb, off] : rings)
          if (c == rb && b <= 30) g += off;
        v(k, j, i) = float(g);
      }
  return v;
}

TEST(Rings, RingsAtKnownRadiiAreFoundAndRemoved) {
  const std::vector<std::pair<int, double>> rings = {{6, 3000}, {14, -2000}, {23, 1500}};
  for (uint64_t seed : {1u, 2u, 3u}) {
    auto v = slices(rings, seed);
    const auto clean = slices({}, seed);
    const RingResult r = remove_rings(v);
    EXPECT_EQ(r.rings, 3) << "seed " << seed;
    EXPECT_DOUBLE_EQ(r.centre_y, 32.0);
    for (const auto& [b, off] : rings) {
      // The bin's mean over 24 slices of ~2 pi b pixels: a standard error of
      // 1500 / sqrt(24 * 2 pi b), 35-63 grey levels; the median of its
      // neighbours adds the profile's slope (80 a bin) at most.
      EXPECT_NEAR(r.offset[size_t(b)], off, 250) << "seed " << seed << " bin " << b;
    }
    // Corrected, every voxel of a ring's bin is its ring-free grey shifted by
    // the offset's error only.
    for (int64_t j = 0; j < 64; ++j) {
      const int b = int(std::floor(std::hypot(double(j) + 0.5 - 32, 0.5)));
      if (b == 14) {
        EXPECT_NEAR(v(5, j, 32), clean(5, j, 32), 250) << "seed " << seed;
      }
    }
  }
}

TEST(Rings, NoRingNoChange) {
  for (uint64_t seed : {4u, 5u, 6u}) {
    auto v = slices({}, seed);
    const auto before = v.clone();
    const RingResult r = remove_rings(v);
    EXPECT_EQ(r.rings, 0) << "seed " << seed << ": the field of view's edge and the slope are no rings";
    for (int64_t i = 0; i < v.size(); ++i) ASSERT_EQ(v[i], before[i]);
  }
}

TEST(Rings, SixteenBitClippedAndThreadCountIndependent) {
  auto f = slices({{10, -8000}, {20, 60000}}, 7);  // the second one clipped at 65535
  Volume<uint16_t> u(f.shape());
  for (int64_t i = 0; i < f.size(); ++i) u[i] = uint16_t(std::clamp(std::lround(double(f[i])), 0L, 65535L));
  auto one = u.clone();
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const RingResult r1 = remove_rings(one);
  omp_set_num_threads(std::max(2, threads));
  const RingResult r2 = remove_rings(u);
  omp_set_num_threads(threads);
  EXPECT_EQ(r1.rings, r2.rings);
  EXPECT_EQ(r1.offset, r2.offset);
  for (int64_t i = 0; i < u.size(); ++i) ASSERT_EQ(u[i], one[i]);
  EXPECT_GE(r1.rings, 1);
}

TEST(Rings, AxisGivenAndBadOptions) {
  // A ring about (20, 24): read about the slice's centre it spreads over
  // many bins, each a fraction of it; about its own axis it is one bin.
  auto v = slices({{9, 2500}}, 8, 20, 24);
  auto w = v.clone();
  const RingResult off_axis = remove_rings(w);
  EXPECT_LT(off_axis.max_offset, 1250);
  RingOptions o;
  o.centre_y = 20, o.centre_x = 24;
  const RingResult r = remove_rings(v, o);
  EXPECT_EQ(r.rings, 1);
  EXPECT_NEAR(r.offset[9], 2500, 250);
  o.window = 4;
  EXPECT_THROW(remove_rings(v, o), UsageError);
  o.window = 7, o.min_z = 0;
  EXPECT_THROW(remove_rings(v, o), UsageError);
}

}  // namespace
}  // namespace tg

#include "core/stats.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace tg {

TEST(Stats, U16ExactHistogramPercentilesAndSaturation) {
  Volume<uint16_t> v(Shape{1, 1, 100});
  for (int i = 0; i < 100; ++i) v[i] = static_cast<uint16_t>(i < 90 ? i : 65535);
  const auto s = compute_stats(AnyVolume(std::move(v)));
  EXPECT_EQ(s.min, 0);
  EXPECT_EQ(s.max, 65535);
  EXPECT_EQ(s.count_at_max, 10);
  EXPECT_EQ(s.percentile(50), 49);  // 50 values 0..49 reach 50 %
  double mean = 0;
  for (int i = 0; i < 90; ++i) mean += i;
  mean = (mean + 10 * 65535.0) / 100;
  EXPECT_DOUBLE_EQ(s.mean, mean);
}

TEST(Stats, FloatNonFiniteCountedAndSkipped) {
  Volume<float> v(Shape{1, 1, 4});
  v[0] = 1;
  v[1] = NAN;
  v[2] = INFINITY;
  v[3] = 3;
  const auto s = compute_stats(AnyVolume(std::move(v)));
  EXPECT_EQ(s.nonfinite, 2);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 3);
  EXPECT_DOUBLE_EQ(s.mean, 2);
}

TEST(Stats, DistinctLabels) {
  Volume<uint32_t> v = Volume<uint32_t>::filled(Shape{2, 2, 2}, 0);
  v[1] = 5;
  v[2] = 5;
  v[3] = 1000;
  const auto s = compute_stats(AnyVolume(std::move(v)));
  EXPECT_EQ(s.distinct_nonzero, 2);
}

}  // namespace tg

#include "core/shape.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace tg {

// A full scan is 1220^3 ~ 1.8e9 voxels; index arithmetic past 2^31 and 2^32
// must be exact. Tested on shapes only: nothing is allocated.
TEST(Shape, IndexPast2To31) {
  const Shape s{1300, 1300, 1300};  // a little larger than the study's 1220^3 scan
  EXPECT_EQ(s.voxels(), int64_t{1300} * 1300 * 1300);
  EXPECT_GT(s.voxels(), int64_t{1} << 31);
  EXPECT_EQ(s.index(1299, 1299, 1299), s.voxels() - 1);
  EXPECT_EQ(s.index(1299, 0, 0), int64_t{1299} * 1300 * 1300);  // 2.195e9: wraps negative in 32 bits
  const auto c = s.coords(s.voxels() - 1);
  EXPECT_EQ(c[0], 1299);
  EXPECT_EQ(c[1], 1299);
  EXPECT_EQ(c[2], 1299);
}

TEST(Shape, IndexPast2To32RoundTrips) {
  const Shape s{3, 50000, 50001};  // 7.5e9 voxels
  for (int64_t k : {0, 1, 2})
    for (int64_t j : {0, 1, 49999})
      for (int64_t i : {0, 7, 50000}) {
        const int64_t idx = s.index(k, j, i);
        EXPECT_EQ(idx, (k * 50000 + j) * 50001 + i);
        const auto c = s.coords(idx);
        EXPECT_EQ(c[0], k);
        EXPECT_EQ(c[1], j);
        EXPECT_EQ(c[2], i);
      }
  EXPECT_GT(s.index(2, 49999, 50000), int64_t{1} << 32);
}

TEST(Shape, VoxelCountOverflowIsAnError) {
  const Shape s{int64_t{1} << 22, int64_t{1} << 22, int64_t{1} << 22};  // 2^66
  EXPECT_THROW(s.voxels(), ResourceError);
  EXPECT_THROW((Shape{-1, 2, 3}.voxels()), UsageError);
}

TEST(Shape, ContainsAndEmpty) {
  const Shape s{2, 3, 4};
  EXPECT_TRUE(s.contains(1, 2, 3));
  EXPECT_FALSE(s.contains(2, 0, 0));
  EXPECT_FALSE(s.contains(0, -1, 0));
  EXPECT_TRUE((Shape{0, 3, 4}.empty()));
}

}  // namespace tg

#include "segmentation/neighbourhood.hpp"

#include <gtest/gtest.h>

#include <set>

namespace tg::seg {
namespace {

TEST(Neighbourhood, CountsAndDistances) {
  const Shape s{5, 6, 7};
  for (int c : {6, 18, 26}) {
    Neighbourhood nb(s, c);
    std::set<int64_t> offs;
    for (int n = 0; n < nb.count; ++n) {
      const Step d = nb.step[size_t(n)];
      const int d2 = d.dz * d.dz + d.dy * d.dy + d.dx * d.dx;
      EXPECT_LE(d2, c == 6 ? 1 : c == 18 ? 2 : 3);
      EXPECT_EQ(nb.offset[size_t(n)], s.index(2 + d.dz, 3 + d.dy, 3 + d.dx) - s.index(2, 3, 3));
      offs.insert(nb.offset[size_t(n)]);
    }
    EXPECT_EQ(int(offs.size()), c);  // all distinct
    EXPECT_EQ(Neighbourhood::backward(s, c).count, c / 2);
  }
  EXPECT_THROW(Neighbourhood(s, 4), UsageError);
}

// A 1300^3 shape (2.2e9 voxels, past 2^31) is never allocated: only the index
// arithmetic is checked, which must not wrap in 32 bits.
TEST(Neighbourhood, SixtyFourBitIndexArithmetic) {
  const Shape s{1300, 1300, 1300};
  EXPECT_EQ(s.voxels(), 2'197'000'000LL);
  const int64_t last = s.index(1299, 1299, 1299);
  EXPECT_EQ(last, 2'196'999'999LL);
  EXPECT_GT(last, int64_t{1} << 31);
  const auto c = s.coords(last);
  EXPECT_EQ(c[0], 1299);
  EXPECT_EQ(c[1], 1299);
  EXPECT_EQ(c[2], 1299);
  Neighbourhood nb(s, 26);
  for (int n = 0; n < nb.count; ++n) {
    const Step d = nb.step[size_t(n)];
    const int64_t from = s.index(1298, 1298, 1298);
    EXPECT_EQ(from + nb.offset[size_t(n)], s.index(1298 + d.dz, 1298 + d.dy, 1298 + d.dx));
  }
  EXPECT_EQ(step_offset(s, {1, 0, 0}), 1'690'000LL);
  EXPECT_TRUE(interior(s, 1298, 1298, 1298));
  EXPECT_FALSE(interior(s, 1299, 5, 5));
}

}  // namespace
}  // namespace tg::seg

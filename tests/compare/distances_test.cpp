// KS and W1 on weighted samples: hand-computed cases, invariances, errors,
// and scipy.stats (Debian's /usr/bin/python3) as an independent implementation.
#include "compare/distances.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "core/errors.hpp"

namespace {
using tg::compare::ks_distance;
using tg::compare::wasserstein1;
using V = std::vector<double>;

TEST(Distances, IdenticalSamplesAreZero) {
  const V a{0.3, 1.0, 2.5, 2.5};
  EXPECT_EQ(ks_distance(a, a), 0.0);
  EXPECT_EQ(wasserstein1(a, a), 0.0);
}

TEST(Distances, ShiftedPointMasses) {
  // Dirac at 1 vs Dirac at 4: KS = 1, W1 = 3.
  EXPECT_DOUBLE_EQ(ks_distance(V{1}, V{4}), 1.0);
  EXPECT_DOUBLE_EQ(wasserstein1(V{1}, V{4}), 3.0);
  // A shift by c moves every quantile by c: W1 = c exactly.
  EXPECT_NEAR(wasserstein1(V{0, 1, 2, 5}, V{0.5, 1.5, 2.5, 5.5}), 0.5, 1e-15);
}

TEST(Distances, HandComputedUnweighted) {
  // a = {1, 2, 3}, b = {2, 4}.
  // Fa: 1/3 on [1,2), 2/3 on [2,3), 1 on [3,inf); Fb: 1/2 on [2,4), 1 on [4,inf).
  // |Fa-Fb|: [1,2) 1/3, [2,3) 1/6, [3,4) 1/2 -> KS = 1/2, W1 = 1/3 + 1/6 + 1/2 = 1.
  EXPECT_DOUBLE_EQ(ks_distance(V{1, 2, 3}, V{2, 4}), 0.5);
  EXPECT_NEAR(wasserstein1(V{1, 2, 3}, V{2, 4}), 1.0, 1e-15);
}

TEST(Distances, HandComputedWeighted) {
  // a = {1 (w 3), 3 (w 1)}: F = 0.75 on [1,3); b = {2 (w 1)}: F = 1 from 2.
  // |Fa-Fb|: [1,2) 0.75, [2,3) 0.25 -> KS = 0.75, W1 = 0.75 + 0.25 = 1.
  EXPECT_DOUBLE_EQ(ks_distance(V{1, 3}, V{2}, V{3, 1}), 0.75);
  EXPECT_NEAR(wasserstein1(V{1, 3}, V{2}, V{3, 1}), 1.0, 1e-15);
  // Integer weights equal repeated values.
  EXPECT_DOUBLE_EQ(ks_distance(V{1, 3}, V{2, 5}, V{3, 1}, V{1, 2}), ks_distance(V{1, 1, 1, 3}, V{2, 5, 5}));
  EXPECT_NEAR(wasserstein1(V{1, 3}, V{2, 5}, V{3, 1}, V{1, 2}), wasserstein1(V{1, 1, 1, 3}, V{2, 5, 5}), 1e-14);
}

TEST(Distances, WeightScaleAndOrderInvariant) {
  const V a{0.5, 2, 1, 7}, wa{1, 2, 3, 4};
  const V a2{7, 1, 2, 0.5}, wa2{40, 30, 20, 10};
  const V b{1.5, 3}, wb{2, 1};
  EXPECT_DOUBLE_EQ(ks_distance(a, b, wa, wb), ks_distance(a2, b, wa2, wb));
  EXPECT_NEAR(wasserstein1(a, b, wa, wb), wasserstein1(a2, b, wa2, wb), 1e-14);
  EXPECT_NEAR(wasserstein1(a, b, wa, wb), wasserstein1(b, a, wb, wa), 1e-14);  // symmetric
}

TEST(Distances, ZeroWeightIsIgnored) {
  EXPECT_DOUBLE_EQ(ks_distance(V{1, 100}, V{1}, V{1, 0}), 0.0);
  EXPECT_DOUBLE_EQ(wasserstein1(V{1, 100}, V{1}, V{1, 0}), 0.0);
}

TEST(Distances, RejectsBadInput) {
  EXPECT_THROW(ks_distance(V{}, V{1}), tg::UsageError);
  EXPECT_THROW(wasserstein1(V{1}, V{NAN}), tg::UsageError);
  EXPECT_THROW(ks_distance(V{1, 2}, V{1}, V{1}), tg::UsageError);
  EXPECT_THROW(ks_distance(V{1, 2}, V{1}, V{1, -1}), tg::UsageError);
  EXPECT_THROW(wasserstein1(V{1, 2}, V{1}, V{0, 0}), tg::UsageError);
}

// scipy.stats.wasserstein_distance (weighted) and ks_2samp (unweighted) on random samples.
TEST(Distances, MatchesScipy) {
  const char* py = "/usr/bin/python3";
  if (!std::filesystem::exists(py) || std::system("/usr/bin/python3 -c 'import scipy.stats' 2>/dev/null") != 0)
    GTEST_SKIP() << "Debian python3-scipy not available";
  std::mt19937_64 rng(5);
  std::lognormal_distribution<double> size(0, 0.4);
  std::uniform_real_distribution<double> w(0.1, 3.0);
  const auto dir = std::filesystem::temp_directory_path() / ("tg_dist_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  struct Case {
    V a, b, wa, wb;
  };
  std::vector<Case> cases;
  for (int c = 0; c < 5; ++c) {
    Case k;
    const int na = 5 + 37 * c, nb = 3 + 23 * c;
    for (int q = 0; q < na; ++q) {
      k.a.push_back(std::round(size(rng) * 100) / 100);  // rounded: ties inside and across samples
      k.wa.push_back(w(rng));
    }
    for (int q = 0; q < nb; ++q) {
      k.b.push_back(std::round(1.2 * size(rng) * 100) / 100);
      k.wb.push_back(w(rng));
    }
    cases.push_back(k);
  }
  auto fmtv = [](const V& v) {
    std::ostringstream s;
    s.precision(17);
    s << "[";
    for (size_t q = 0; q < v.size(); ++q) s << (q ? "," : "") << v[q];
    return s.str() + "]";
  };
  {
    std::ofstream f(dir / "check.py");
    f << "import scipy.stats as st\ncases = [\n";
    for (const Case& k : cases) f << "(" << fmtv(k.a) << "," << fmtv(k.b) << "," << fmtv(k.wa) << "," << fmtv(k.wb) << "),\n";
    f << "]\nfor a, b, wa, wb in cases:\n"
         "    print(repr(st.wasserstein_distance(a, b, wa, wb)), repr(st.wasserstein_distance(a, b)),"
         " repr(st.ks_2samp(a, b).statistic))\n";
  }
  const std::string cmd = std::string(py) + " " + (dir / "check.py").string() + " > " + (dir / "out.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(dir / "out.txt");
  for (const Case& k : cases) {
    double w1w = 0, w1 = 0, ks = 0;
    ASSERT_TRUE(in >> w1w >> w1 >> ks);
    EXPECT_NEAR(wasserstein1(k.a, k.b, k.wa, k.wb), w1w, 1e-12 * (1 + w1w));
    EXPECT_NEAR(wasserstein1(k.a, k.b), w1, 1e-12 * (1 + w1));
    EXPECT_NEAR(ks_distance(k.a, k.b), ks, 1e-12);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace

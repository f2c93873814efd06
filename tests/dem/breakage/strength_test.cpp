#include "dem/breakage/strength.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "core/errors.hpp"

using namespace tg::dem::breakage;

namespace {
std::vector<double> draw(const StrengthParams& p, double d, int n, uint64_t key0 = 0) {
  std::vector<double> s(n);
  for (int i = 0; i < n; ++i) s[i] = sphere_strength(p, key0 + i, d);
  return s;
}
}  // namespace

// Kolmogorov–Smirnov distance of 20 000 draws at d = d0 against the Weibull
// CDF F(σ) = 1 − exp[−(σ/σt0)^m]; the 1 % critical value is 1.63/√n = 0.0115.
TEST(Strength, MatchesWeibullCdfKolmogorovSmirnov) {
  const StrengthParams p{};
  for (double d : {p.d0_m, 0.4e-3}) {
    const int n = 20000;
    auto s = draw(p, d, n);
    std::sort(s.begin(), s.end());
    double dmax = 0;
    for (int i = 0; i < n; ++i) {
      const double f = 1 - survival_probability(p, d, s[i]);
      dmax = std::max({dmax, std::abs(f - double(i) / n), std::abs(f - double(i + 1) / n)});
    }
    EXPECT_LT(dmax, 1.63 / std::sqrt(double(n))) << "d = " << d;
  }
}

TEST(Strength, MedianFollowsSizeEffect) {
  // Median = σt0 (d0/d)^(3/m) (ln 2)^(1/m): 10.5 MPa at d0, half of it at 2 d0 (m = 3).
  const StrengthParams p{};
  for (double f : {0.5, 1.0, 2.0}) {
    auto s = draw(p, f * p.d0_m, 20001, 1000000);
    std::nth_element(s.begin(), s.begin() + 10000, s.end());
    const double expected = 12e6 / f * std::cbrt(std::log(2.0));
    // Standard error of a sample median: 1/(2 f(med) √n) ≈ 0.6 % here; 2 % tolerance.
    EXPECT_NEAR(s[10000] / expected, 1.0, 0.02) << f;
  }
}

TEST(Strength, PureFunctionOfSeedAndKey) {
  StrengthParams p{};
  const double a = sphere_strength(p, 42, 1e-3);
  draw(p, 1e-3, 1000);  // other draws in between change nothing
  EXPECT_EQ(sphere_strength(p, 42, 1e-3), a);
  p.seed = 2;
  EXPECT_NE(sphere_strength(p, 42, 1e-3), a);
  // Fragment keys: distinct over three generations of a few mothers.
  std::set<uint64_t> keys;
  for (uint64_t m = 0; m < 20; ++m)
    for (int s = 0; s < 34; ++s) {
      const uint64_t k = fragment_key(m, s);
      keys.insert(k);
      for (int t = 0; t < 34; ++t) keys.insert(fragment_key(k, t));
    }
  EXPECT_EQ(keys.size(), 20u * 34u * 35u);
}

TEST(Strength, UniformNeverHitsTheEnds) {
  for (uint64_t k = 0; k < 100000; ++k) {
    const double u = strength_uniform(7, k);
    ASSERT_GT(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
}

TEST(Strength, RejectsBadParameters) {
  StrengthParams p{};
  p.weibull_modulus = 0;
  EXPECT_THROW(validate(p), tg::InputError);
  p = {};
  p.d0_m = -1;
  EXPECT_THROW(validate(p), tg::InputError);
  EXPECT_NO_THROW(validate(StrengthParams{}));
}

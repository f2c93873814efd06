#include "measure/psd.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace tg::measure {
namespace {

TEST(Psd, PercentPassingHandTable) {
  // Sizes 0.15, 0.3, 0.3, 0.7, 1.1 mm with masses 1, 2, 1, 4, 2 (total 10).
  const std::vector<double> d{0.15, 0.3, 0.3, 0.7, 1.1}, m{1, 2, 1, 4, 2}, s{0.1, 0.2, 0.4, 0.8, 1.6};
  const auto p = percent_passing(d, m, s);
  const std::vector<double> want{0, 10, 40, 80, 100};
  for (size_t k = 0; k < s.size(); ++k) EXPECT_NEAR(p[k], want[k], 1e-12);
  // A particle exactly at a sieve size passes it.
  EXPECT_NEAR(percent_passing(std::vector<double>{0.2}, std::vector<double>{1}, s)[1], 100, 1e-12);
}

TEST(Psd, QuantilesLogLinear) {
  const std::vector<double> s{0.1, 0.2, 0.4, 0.8, 1.6}, p{0, 10, 40, 80, 100};
  EXPECT_NEAR(grading_quantile(s, p, 10), 0.2, 1e-12);                        // on a sieve
  EXPECT_NEAR(grading_quantile(s, p, 50), 0.4 * std::pow(2.0, 0.25), 1e-12);  // 1/4 of the way 40 -> 80 in log size
  EXPECT_NEAR(grading_quantile(s, p, 60), 0.4 * std::pow(2.0, 0.5), 1e-12);
  EXPECT_TRUE(std::isnan(grading_quantile(s, std::vector<double>{20, 30, 40, 80, 100}, 10)));  // below the finest sieve
}

TEST(Psd, ClassPercent) {
  const std::vector<double> fr{0.3, 0.5, 0.85, 0.95, 0.99, 1.02, 0.8, 0.9};
  const auto c = class_percent(fr, fr_thresholds());
  ASSERT_EQ(c.size(), 4u);
  EXPECT_NEAR(c[0], 12.5, 1e-12);  // 0.3
  EXPECT_NEAR(c[1], 12.5, 1e-12);  // 0.5
  EXPECT_NEAR(c[2], 25.0, 1e-12);  // 0.85, 0.8 (lower edge included)
  EXPECT_NEAR(c[3], 50.0, 1e-12);  // 0.95, 0.99, 1.02, 0.9
}

TEST(Psd, HardinHandComputed) {
  // Initial F0: 0 at 0.1 mm, 1 at 1 mm (linear in log10 d): Bp0 = 1/2 decade.
  // Current F: 0.5 at 0.1 mm, 1 at 1 mm: Bp = 1/4. Br = 1/2.
  const std::vector<double> s{0.1, 1.0}, f0{0, 100}, f1{50, 100};
  EXPECT_NEAR(hardin_potential(s, f0, 0.1), 0.5, 1e-12);
  EXPECT_NEAR(hardin_potential(s, f1, 0.1), 0.25, 1e-12);
  EXPECT_NEAR(hardin_br(s, f0, f1, 0.1), 0.5, 1e-12);
  // A cut-off below the finest sieve: fines spread evenly in log size from it.
  // F0 is then 0 on [0.01, 0.1]: Bp0 = 1 + 0.5.
  EXPECT_NEAR(hardin_potential(s, f0, 0.01), 1.5, 1e-12);
  EXPECT_NEAR(hardin_br(s, f0, f0), 0.0, 1e-12);
}

TEST(Psd, EinavHandComputed) {
  // Sieves 0.1, 0.5, 1 mm; initial F0 = 0, 0, 100 %; current F = 10, 20, 100 %.
  // On x = log10 d (curves linear in x between sieves):
  //   integral F0 = 0.5 * L2, integral F = 0.15 * L1 + 0.6 * L2,
  //   L1 = log10(0.5 / 0.1), L2 = log10(1 / 0.5);
  // ultimate Fu(d) = (d^0.4 - 0.1^0.4) / (1 - 0.1^0.4) on [0.1, 1]:
  //   integral Fu = ((1 - 0.1^0.4) / (0.4 ln 10) - 0.1^0.4) / (1 - 0.1^0.4).
  const std::vector<double> s{0.1, 0.5, 1.0}, f0{0, 0, 100}, f1{10, 20, 100};
  const double L1 = std::log10(5.0), L2 = std::log10(2.0);
  const double a = std::pow(0.1, 0.4);
  const double iu = ((1 - a) / (0.4 * std::log(10.0)) - a) / (1 - a);
  const double i0 = 0.5 * L2, i1 = 0.15 * L1 + 0.6 * L2;
  EXPECT_NEAR(einav_br(s, f0, f1), (i1 - i0) / (iu - i0), 1e-9);
  EXPECT_NEAR(einav_br(s, f0, f0), 0.0, 1e-12);
  // Reaching the ultimate grading gives Br* = 1 (sampled finely enough that
  // the piecewise-linear curve follows Fu).
  std::vector<double> fine, fu, fi;
  for (int k = 0; k <= 400; ++k) {
    const double d = std::pow(10.0, -1 + k / 400.0);
    fine.push_back(d);
    fu.push_back(100 * (std::pow(d, 0.4) - a) / (1 - a));
    fi.push_back(100 * std::clamp((std::log10(d) - std::log10(0.9)) / -std::log10(0.9), 0.0, 1.0));
  }
  EXPECT_NEAR(einav_br(fine, fi, fu), 1.0, 1e-5);
  EinavOptions o;
  o.fractal_dimension = 3.2;
  EXPECT_THROW(einav_br(s, f0, f1, o), UsageError);
}

TEST(Psd, RejectsBadInput) {
  EXPECT_THROW(percent_passing(std::vector<double>{1}, std::vector<double>{1}, std::vector<double>{0.2, 0.1}),
               UsageError);
  EXPECT_THROW(percent_passing(std::vector<double>{1}, std::vector<double>{0}, std::vector<double>{0.1, 2}),
               InputError);
}

}  // namespace
}  // namespace tg::measure

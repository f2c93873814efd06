// measure/grading: which particles count, D-values from the sorted table,
// sieves, class names and whole-stage gradings.
#include "measure/grading.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace tg::measure {
namespace {

Table particles(std::vector<double> d, std::vector<double> fr, std::vector<double> ar, std::vector<double> below) {
  Table t;
  std::vector<double> v;
  for (double x : d) v.push_back(std::numbers::pi / 6 * x * x * x);
  t.add("d_med_mm", d);
  t.add("volume_mm3", v);
  t.add("fr", fr);
  t.add("ar", ar);
  t.add("below_limit", below);
  return t;
}

TEST(Grading, BelowLimitCountsInMassNotInShape) {
  const auto s = grading_sample(particles({1.0, 0.1, 1.2}, {0.95, 0.3, 0.5}, {1.1, 3.5, 2.5}, {0, 1, 0}));
  EXPECT_EQ(s.size_mm.size(), 3u);
  EXPECT_EQ(s.fr, (std::vector<double>{0.95, 0.5}));
  EXPECT_EQ(s.ar, (std::vector<double>{1.1, 2.5}));
  SampleRules drop;
  drop.exclude_below_limit = true;
  EXPECT_EQ(grading_sample(particles({1.0, 0.1, 1.2}, {0.95, 0.3, 0.5}, {1.1, 3.5, 2.5}, {0, 1, 0}), drop).size_mm,
            (std::vector<double>{1.0, 1.2}));
}

TEST(Grading, SortedQuantileByHand) {
  // Sizes 1 and 2 mm with masses 1 and 3: F = 25 % at 1, 100 % at 2.
  const std::vector<double> d{2, 1}, m{3, 1};
  EXPECT_EQ(sorted_quantile(d, m, 10), 1.0);  // below the finest particle's share
  EXPECT_NEAR(sorted_quantile(d, m, 50), std::pow(2.0, 25.0 / 75.0), 1e-15);
  EXPECT_NEAR(sorted_quantile(d, m, 60), std::pow(2.0, 35.0 / 75.0), 1e-15);
  EXPECT_EQ(sorted_quantile(d, m, 100), 2.0);
  EXPECT_TRUE(std::isnan(sorted_quantile({}, {}, 50)));
}

// Independent check: the sieve-based reading of measure/psd with a sieve at
// every particle size is the same curve, so the quantiles agree (seeds 1-3).
TEST(Grading, SortedQuantileEqualsSievesAtEveryParticle) {
  for (unsigned seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    std::lognormal_distribution<double> size(std::log(1.3), 0.05 * seed);
    std::vector<double> d(200), m(200);
    for (size_t i = 0; i < d.size(); ++i) {
      d[i] = size(rng);
      m[i] = d[i] * d[i] * d[i];
    }
    std::vector<double> sieves = d;
    std::sort(sieves.begin(), sieves.end());
    const auto pass = percent_passing(d, m, sieves);
    for (double p : {10.0, 30.0, 50.0, 60.0, 90.0})
      EXPECT_NEAR(sorted_quantile(d, m, p), grading_quantile(sieves, pass, p), 1e-12) << seed << " " << p;
  }
}

TEST(Grading, DefaultSievesAreR40AndCoverEverySize) {
  const auto base = default_sieves_mm();
  EXPECT_NEAR(base.front(), 0.1, 1e-12);
  EXPECT_NEAR(base.back(), std::pow(10.0, 0.4), 1e-12);
  for (size_t k = 1; k < base.size(); ++k) EXPECT_NEAR(base[k] / base[k - 1], std::pow(10.0, 1.0 / 40), 1e-12);
  GradingSample a;
  a.size_mm = {0.05, 3.1};
  const GradingSample* p[] = {&a};
  const auto s = sieves_covering({}, p);
  EXPECT_LE(s.front(), 0.05);
  EXPECT_GT(s.front(), 0.05 / std::pow(10.0, 1.0 / 40));  // one R40 step at most below
  EXPECT_GE(s.back(), 3.1);
  for (size_t k = 1; k < s.size(); ++k) EXPECT_NEAR(s[k] / s[k - 1], std::pow(10.0, 1.0 / 40), 1e-9);
  const std::vector<double> user{0.2, 0.4, 0.8};  // a user's set, extended above
  const auto u = sieves_covering(user, p);
  EXPECT_GE(u.back(), 3.1);
  EXPECT_LE(u.front(), 0.05);
  EXPECT_NE(std::find(u.begin(), u.end(), 0.4), u.end());
}

TEST(Grading, ClassLabelsAndColumns) {
  EXPECT_EQ(class_labels(fr_thresholds()), (std::vector<std::string>{"<0.4", "0.4-0.8", "0.8-0.9", ">=0.9"}));
  EXPECT_EQ(class_labels(ar_thresholds()), (std::vector<std::string>{"<2", "2-3", ">=3"}));
  EXPECT_EQ(class_columns("fr", fr_thresholds()),
            (std::vector<std::string>{"fr_lt_0.4_pct", "fr_0.4_0.8_pct", "fr_0.8_0.9_pct", "fr_ge_0.9_pct"}));
}

TEST(Grading, MonodisperseStagesAndEmptyStage) {
  const auto s = grading_sample(particles({1, 1, 1, 1}, {0.3, 0.5, 0.85, 0.95}, {1.5, 1.5, 2.5, 3.5}, {0, 0, 0, 0}));
  const GradingSample* p[] = {&s};
  const auto sv = sieves_covering({}, p);
  const std::vector<GradingSample> stages{s, s, GradingSample{}};
  const auto g = grade_stages(stages, sv);
  for (size_t k = 0; k < sv.size(); ++k) EXPECT_EQ(g[0].passing[k], sv[k] >= 1 - 1e-12 ? 100.0 : 0.0) << sv[k];
  EXPECT_EQ(g[0].fr_classes, (std::vector<double>{25, 25, 25, 25}));
  EXPECT_EQ(g[0].ar_classes, (std::vector<double>{50, 25, 25}));
  EXPECT_EQ(g[0].particles, 4);
  EXPECT_EQ(g[0].d.d10, 1.0);
  EXPECT_EQ(g[0].d.cu, 1.0);
  EXPECT_EQ(g[1].hardin_br, 0.0);  // the same grading as the first: no breakage
  EXPECT_TRUE(std::isnan(g[2].d.d50));
  EXPECT_TRUE(std::isnan(g[2].hardin_br));
}

}  // namespace
}  // namespace tg::measure

// Stage metrics from particle tables: sample selection, sieves, classes, distances.
#include "compare/stage_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {
using namespace tg;

Table particles(std::vector<double> d, std::vector<double> fr, std::vector<double> ar, std::vector<double> below) {
  Table t;
  std::vector<double> v;
  for (double x : d) v.push_back(std::acos(-1.0) / 6 * x * x * x);
  t.add("d_med_mm", d);
  t.add("volume_mm3", v);
  t.add("fr", fr);
  t.add("ar", ar);
  t.add("below_limit", below);
  return t;
}

TEST(StageMetrics, BelowLimitCountsInPsdNotInShape) {
  const auto s = compare::sample_from_table(particles({1.0, 0.1, 1.2}, {0.95, 0.3, 0.5}, {1.1, 3.5, 2.5}, {0, 1, 0}));
  EXPECT_EQ(s.dmed_mm.size(), 3u);
  EXPECT_EQ(s.fr, (std::vector<double>{0.95, 0.5}));
  EXPECT_EQ(s.ar, (std::vector<double>{1.1, 2.5}));
}

TEST(StageMetrics, SievesCoverEverySize) {
  compare::StageSample a;
  a.dmed_mm = {0.05, 3.1};
  const compare::StageSample* p[] = {&a};
  const auto s = compare::sieves_for(p);
  EXPECT_LE(s.front(), 0.05);
  EXPECT_GE(s.back(), 3.1);
  for (size_t k = 1; k < s.size(); ++k) EXPECT_NEAR(s[k] / s[k - 1], std::pow(10.0, 0.1), 1e-12);
}

TEST(StageMetrics, MonodisperseGradingAndClasses) {
  // All particles 1 mm: passing 0 below the 1 mm sieve, 100 % from it.
  const auto s = compare::sample_from_table(particles({1, 1, 1, 1}, {0.3, 0.5, 0.85, 0.95}, {1.5, 1.5, 2.5, 3.5},
                                                      {0, 0, 0, 0}));
  const compare::StageSample* p[] = {&s};
  const auto sv = compare::sieves_for(p);
  const auto m = compare::stage_metrics(s, sv);
  for (size_t k = 0; k < sv.size(); ++k) EXPECT_EQ(m.passing[k], sv[k] >= 1 - 1e-12 ? 100.0 : 0.0) << sv[k];
  EXPECT_EQ(m.fr_classes, (std::vector<double>{25, 25, 25, 25}));
  EXPECT_EQ(m.ar_classes, (std::vector<double>{50, 25, 25}));
  EXPECT_EQ(m.particles, 4);
}

TEST(StageMetrics, DistancesOfSameSampleAreZeroAndEmptyIsNaN) {
  const auto s = compare::sample_from_table(particles({1, 2}, {0.9, 0.5}, {1.2, 2.2}, {0, 0}));
  const auto d = compare::sample_distances(s, s);
  EXPECT_EQ(d.psd_ks, 0);
  EXPECT_EQ(d.ar_w1, 0);
  compare::StageSample empty;
  EXPECT_TRUE(std::isnan(compare::sample_distances(s, empty).psd_ks));
  // By mass: the 2 mm particle carries 8/9 of the mass. Against a lone 2 mm particle:
  // KS = F_a(1) - 0 = 1/9; W1 = (1/9) * (2 - 1).
  compare::StageSample b;
  b.dmed_mm = {2};
  b.volume_mm3 = {1};
  const auto e = compare::sample_distances(s, b);
  EXPECT_NEAR(e.psd_ks, 1.0 / 9, 1e-12);
  EXPECT_NEAR(e.psd_w1_mm, 1.0 / 9, 1e-12);
}

}  // namespace

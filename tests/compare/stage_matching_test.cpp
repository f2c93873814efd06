// compare/stage_matching: pairing stages with snapshots, broken fractions,
// curves; and the distances between two stages' samples.
#include "compare/stage_matching.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "compare/distances.hpp"
#include "core/errors.hpp"

namespace tg::compare {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(StageMatching, NearestStrainElseByOrder) {
  const std::vector<double> snap{0.0, 0.044, 0.0712, 0.1128, 0.1548};
  EXPECT_EQ(match_snapshot(snap, 0.07, 0), 2u);
  EXPECT_EQ(match_snapshot(snap, 0.2, 0), 4u);
  EXPECT_EQ(match_snapshot(snap, kNaN, 3), 3u);   // unknown stage strain: by order
  EXPECT_EQ(match_snapshot(snap, kNaN, 9), 4u);   // clamped to the last snapshot
  const std::vector<double> unknown{kNaN, kNaN};
  EXPECT_EQ(match_snapshot(unknown, 0.05, 1), 1u);  // unknown snapshot strains: by order
  EXPECT_THROW(match_snapshot(std::vector<double>{}, 0.0, 0), UsageError);
}

TEST(StageMatching, DemBrokenFractionFromHistoryElseCountGrowth) {
  Curve h;
  h.strain = {0.0, 0.1};
  h.broken = {0.0, 100.0};
  const BrokenEstimate a = dem_broken_fraction(h, 0.05, 999, 200);  // linear: 50 of 200 grains
  EXPECT_DOUBLE_EQ(a.fraction, 0.25);
  EXPECT_NE(a.method.find("history"), std::string::npos);
  Curve none;
  EXPECT_DOUBLE_EQ(dem_broken_fraction(none, 0.05, 150, 100).fraction, 0.5);  // 50 extra particles
  EXPECT_DOUBLE_EQ(dem_broken_fraction(none, 0.05, 90, 100).fraction, 0.0);   // clamped
  EXPECT_DOUBLE_EQ(dem_broken_fraction(none, 0.05, 400, 100).fraction, 1.0);
  EXPECT_DOUBLE_EQ(dem_broken_fraction(h, kNaN, 150, 100).fraction, 0.5);      // strain unknown
  EXPECT_TRUE(std::isnan(count_growth_fraction(5, 0)));
}

TEST(StageMatching, InterpolateBracketsElseNearest) {
  const std::vector<double> x{0, 1, 2}, y{0, 10, 40};
  EXPECT_DOUBLE_EQ(interpolate(x, y, 1.5), 25);
  EXPECT_DOUBLE_EQ(interpolate(x, y, 3), 40);
  EXPECT_DOUBLE_EQ(interpolate(x, y, -1), 0);
  EXPECT_TRUE(std::isnan(interpolate({}, {}, 0)));
}

TEST(StageMatching, CurveUnitsFromTheColumnName) {
  const auto f = std::filesystem::temp_directory_path() / ("tg_curve_" + std::to_string(::getpid()) + ".csv");
  { std::ofstream(f) << "axial_strain,axial_stress_kPa,broken\n0,0,0\n0.1,2500,7\n"; }
  const Curve c = read_curve(f);
  EXPECT_EQ(c.stress_column, "axial_stress_kPa");
  EXPECT_DOUBLE_EQ(c.stress_mpa[1], 2.5);
  EXPECT_EQ(c.broken, (std::vector<double>{0, 7}));
  { std::ofstream(f) << "strain,sigma\n0,1\n"; }
  EXPECT_THROW(read_curve(f), InputError);
  std::filesystem::remove(f);
  Table hist;
  hist.add("step", {0, 10});
  hist.add("strain", {0, 0.01});
  hist.add("top_stress_Pa", {0, 3e6});
  const Curve d = history_curve(hist);
  EXPECT_DOUBLE_EQ(d.stress_mpa[1], 3.0);
  EXPECT_TRUE(d.broken.empty());
  EXPECT_TRUE(history_curve(Table{}).strain.empty());
}

TEST(Distances, SameSampleIsZeroEmptyIsNaNAndMassWeighted) {
  measure::GradingSample s;
  s.size_mm = {1, 2};
  s.mass = {1, 8};
  s.fr = {0.9, 0.5};
  s.ar = {1.2, 2.2};
  const auto d = sample_distances(s, s);
  EXPECT_EQ(d.psd_ks, 0);
  EXPECT_EQ(d.ar_w1, 0);
  EXPECT_TRUE(std::isnan(sample_distances(s, measure::GradingSample{}).psd_ks));
  // By mass the 2 mm particle carries 8/9. Against a lone 2 mm particle:
  // KS = F_a(1) - 0 = 1/9; W1 = (1/9) * (2 - 1).
  measure::GradingSample b;
  b.size_mm = {2};
  b.mass = {1};
  const auto e = sample_distances(s, b);
  EXPECT_NEAR(e.psd_ks, 1.0 / 9, 1e-12);
  EXPECT_NEAR(e.psd_w1_mm, 1.0 / 9, 1e-12);
  EXPECT_TRUE(std::isnan(e.fr_ks));
}

}  // namespace
}  // namespace tg::compare

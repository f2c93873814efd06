#include "dem/pluviation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace tg::dem {
namespace {

TEST(Pluviation, SigmaFromUniformityCoefficient) {
  // D60/D10 of N(μ, σ) with the quantiles z60 = 0.2533, z10 = -1.2816.
  const double s = sigma_from_cu(1.36e-3, 1.07);
  EXPECT_NEAR(s, 0.0586e-3, 0.0001e-3);  // the LIGGGHTS peer's σ
  EXPECT_NEAR((1.36e-3 + 0.2533 * s) / (1.36e-3 - 1.2816 * s), 1.07, 1e-12);
}

TEST(Pluviation, InsertionIsNonOverlappingAndFillsTargetVolume) {
  PluviationOptions o;  // the study's cell: Ø15 × 30 mm, H 12.25 mm at 44.5 %
  const Particles p = insert_grains(o, 2180);
  double v = 0;
  for (int64_t i = 0; i < p.size(); ++i) {
    v += 4.0 / 3.0 * std::numbers::pi * std::pow(p.r[i], 3);
    EXPECT_LE(std::hypot(p.x[i], p.y[i]) + p.r[i], o.cylinder_radius_m);
    EXPECT_GE(p.z[i] - p.r[i], 0);
    EXPECT_LE(p.z[i] + p.r[i], o.generation_height_m);
  }
  const double vt = (1 - o.target_porosity) * std::numbers::pi * std::pow(o.cylinder_radius_m, 2) * o.target_height_m;
  EXPECT_GE(v, vt);
  EXPECT_LT(v - vt, 4.0 / 3.0 * std::numbers::pi * std::pow(1.6e-3 / 2, 3));  // at most one grain over
  EXPECT_GT(p.size(), 850);
  EXPECT_LT(p.size(), 960);
  int64_t overlaps = 0;
  for (int64_t i = 0; i < p.size(); ++i)
    for (int64_t j = i + 1; j < p.size(); ++j)
      overlaps += std::hypot(p.x[i] - p.x[j], p.y[i] - p.y[j], p.z[i] - p.z[j]) < p.r[i] + p.r[j];
  EXPECT_EQ(overlaps, 0);
}

TEST(Pluviation, SmallSpecimenSettles) {
  PluviationOptions o;
  o.cylinder_radius_m = 2.5e-3;
  o.generation_height_m = 6e-3;
  o.target_height_m = 2e-3;
  o.max_time_s = 0.3;
  const PluviationResult r = pluviate(o, EngineOptions{});
  EXPECT_TRUE(r.settled);
  EXPECT_LT(r.kinetic_energy_J, o.kinetic_energy_tol_J);
  EXPECT_GT(r.porosity, 0.3);
  EXPECT_LT(r.porosity, 0.7);
  for (int64_t i = 0; i < r.particles.size(); ++i) EXPECT_LT(r.particles.z[i], 4 * 1.36e-3);  // fell down
}

// Densification (issue 6): the same grains deposited without friction pack
// denser than with the study's μ = 0.5 (frictionless spheres cannot hold the
// arches that friction does), and both packings stay free of overlaps
// (settled overlaps are elastic, < 1e-3 r).
TEST(Pluviation, FrictionlessDepositionPacksDenserWithoutOverlap) {
  PluviationOptions o;
  o.cylinder_radius_m = 3.5e-3;
  o.generation_height_m = 10e-3;
  o.target_height_m = 4e-3;  // ~65 grains
  o.max_time_s = 0.5;
  auto run = [&](double mu) {
    PluviationOptions q = o;
    q.deposition_friction = mu;
    const PluviationResult r = pluviate(q, EngineOptions{});
    EXPECT_TRUE(r.settled) << "mu " << mu;
    const Particles& p = r.particles;
    double worst = 0;
    for (int64_t i = 0; i < p.size(); ++i) {
      worst = std::max(worst, (p.r[i] - p.z[i]) / p.r[i]);
      worst = std::max(worst, (std::hypot(p.x[i], p.y[i]) + p.r[i] - o.cylinder_radius_m) / p.r[i]);
      for (int64_t j = i + 1; j < p.size(); ++j)
        worst = std::max(worst, (p.r[i] + p.r[j] - std::hypot(p.x[i] - p.x[j], p.y[i] - p.y[j], p.z[i] - p.z[j])) /
                                    std::min(p.r[i], p.r[j]));
    }
    EXPECT_LT(worst, 1e-3) << "mu " << mu;
    return r;
  };
  const PluviationResult rough = run(0.5), smooth = run(0.0);
  ASSERT_EQ(rough.particles.size(), smooth.particles.size());  // same grains
  for (int64_t i = 0; i < rough.particles.size(); ++i) ASSERT_EQ(rough.particles.r[i], smooth.particles.r[i]);
  std::printf("porosity: mu 0.5 %.4f, mu 0 %.4f\n", rough.porosity, smooth.porosity);
  EXPECT_LT(smooth.porosity, rough.porosity - 0.01);  // measured: 0.5733 vs 0.5470
}

}  // namespace
}  // namespace tg::dem

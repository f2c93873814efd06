#include "dem/time_step.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/errors.hpp"

namespace tg::dem {
namespace {

TEST(TimeStep, HandComputedValues) {
  Particles p;
  p.append_sphere(0, 0, 0, 0.6e-3, 2180, 0);
  p.append_sphere(0, 0, 0, 0.7e-3, 2180, 1);
  const Material mat;
  const CriticalTimeStep c = critical_time_step(p, mat, {0.05});
  // E = 2G(1+ν) = 5.5 GPa; E* = E / (2 (1-ν²)); kn = 2 E* sqrt(R* δ), R* = r_max, δ = 0.05 r_max.
  const double estar = 5.5e9 / (2 * (1 - 0.0625));
  const double k = 2 * estar * std::sqrt(0.7e-3 * 0.05 * 0.7e-3);
  const double m = 2180 * 4.0 / 3.0 * std::numbers::pi * std::pow(0.6e-3, 3);
  EXPECT_NEAR(c.k_max / k, 1.0, 1e-12);
  EXPECT_NEAR(c.dt_hertz / std::sqrt(m / k), 1.0, 1e-12);
  EXPECT_NEAR(c.dt_rayleigh / (std::numbers::pi * 0.6e-3 * std::sqrt(2180 / 2.2e9) / (0.1631 * 0.25 + 0.8766)), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(c.dt_critical, std::min(c.dt_hertz, c.dt_rayleigh));
}

TEST(TimeStep, RejectsEmpty) {
  EXPECT_THROW(critical_time_step(Particles{}, Material{}, {}), InputError);
}

}  // namespace
}  // namespace tg::dem

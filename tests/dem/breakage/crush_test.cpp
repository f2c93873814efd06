#include "dem/breakage/crush.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "dem/breakage/fragment_template.hpp"

using namespace tg::dem;
using namespace tg::dem::breakage;

namespace {
// One run shared by the tests (~10⁵ steps): 1.2 mm grain, Table 1
// parameters, platen travel 9 % of d: the grain splits, then an element of a
// fragment splits again (sequential breakage), and bonds break.
const CrushResult& crush_once() {
  static const CrushResult res = [] {
    CrushOptions o;
    o.final_travel_fraction = 0.09;
    return run_crush(o);
  }();
  return res;
}
}  // namespace

// The grain splits at the platen travel where the Hertz force of two
// sphere–platen contacts in series, F = 4/3 E* √r (u/2)^{3/2}, reaches its
// strength × d² (independent prediction), within one check interval of
// travel plus 3 % for the dynamics of a 0.1 m/s platen.
TEST(Crush, SplitsWhenForceOverDiameterSquaredExceedsStrength) {
  const CrushOptions o;
  const CrushResult& res = crush_once();
  ASSERT_GE(res.splits.size(), 1u);
  const SplitEvent& ev = res.splits.front();
  EXPECT_EQ(ev.generation, 0);
  EXPECT_EQ(ev.sphere, 0);
  const double d = o.diameter_m, r = d / 2;
  EXPECT_GT(ev.stress_Pa, res.strength_Pa);
  EXPECT_NEAR(ev.f_max_N / (d * d), ev.stress_Pa, 1e-9 * ev.stress_Pa);
  const Material m;
  const double e_star = m.youngs_modulus() / (2 * (1 - m.poisson_ratio * m.poisson_ratio));
  const double u_pred = 2 * std::pow(res.strength_Pa * d * d / (4.0 / 3.0 * e_star * std::sqrt(r)), 2.0 / 3.0);
  const double u_split = ev.step * res.time_step_initial_s * o.platen_speed_m_s;
  const double du_interval = o.breakage.check_interval * res.time_step_initial_s * o.platen_speed_m_s;
  EXPECT_NEAR(u_split, u_pred, 0.03 * u_pred + du_interval) << "strength " << res.strength_Pa;
  // At the previous check the stress was below the strength: the split came
  // at the first check over it (the force grows monotonically before it).
  const double u_prev = u_split - du_interval;
  const double f_prev = 4.0 / 3.0 * e_star * std::sqrt(r) * std::pow(0.5 * u_prev, 1.5);
  EXPECT_LT(f_prev / (d * d), res.strength_Pa * 1.05);
}

TEST(Crush, SplitsAlongThePredictedPlaneWithTheTemplateVolume) {
  const CrushResult& res = crush_once();
  ASSERT_GE(res.splits.size(), 1u);
  const SplitEvent& ev = res.splits.front();
  // Two platen contacts: σ2 = σ3 and n_f ∥ e1 = z → fixed-axis rule, plane x = 0.
  EXPECT_EQ(ev.plane.rule, PlaneRule::kFixedAxis);
  EXPECT_NEAR(std::abs(ev.plane.n_f.z), 1, 1e-9);
  EXPECT_NEAR(ev.plane.normal.x, 1, 1e-9);
  EXPECT_NEAR(ev.volume_retained_m3 / ev.volume_mother_m3, fragment_template().retained_fraction(), 1e-12);
  EXPECT_NEAR(ev.volume_retained_m3 / ev.volume_mother_m3, 0.5404, 1e-4);
}

// After the split the two fragments keep carrying the platen load and their
// bonds break under further loading; the time step was lowered for the
// small spheres.
TEST(Crush, FragmentsCarryLoadAndBondsBreakLater) {
  const CrushResult& res = crush_once();
  ASSERT_GE(res.splits.size(), 1u);
  const int64_t split_step = res.splits.front().step;
  double f_after = 0;
  for (const auto& row : res.history)
    if (row.step > split_step) f_after = std::max(f_after, row.force_N);
  EXPECT_GT(f_after, 0.05 * res.splits.front().f_max_N);
  EXPECT_GT(res.final_record.bonds_broken, 0);
  EXPECT_GE(res.final_record.spheres, 34);
  EXPECT_GE(res.final_record.particles, 2);
  EXPECT_EQ(res.final_record.grains_broken, 1);
  EXPECT_LT(res.time_step_final_s, res.time_step_initial_s);
}

// Sequential breakage: a cluster element (d ≥ 0.2 mm) splits again by the
// same rule; its bonds leave with it (recorded apart from stress breakage).
TEST(Crush, ClusterElementSplitsAgain) {
  const CrushResult& res = crush_once();
  ASSERT_GE(res.splits.size(), 2u);
  const SplitEvent& ev = res.splits[1];
  EXPECT_EQ(ev.generation, 1);
  EXPECT_GE(ev.diameter_m, 2e-4);
  EXPECT_GT(ev.stress_Pa, ev.strength_Pa);
  ASSERT_GE(res.final_record.splits_by_generation.size(), 2u);
  EXPECT_EQ(res.final_record.splits_by_generation[0], 1);
  EXPECT_GE(res.final_record.splits_by_generation[1], 1);
  EXPECT_GT(res.final_record.bonds_dropped, 0);
  EXPECT_EQ(res.final_record.spheres, 1 + 33 * static_cast<int64_t>(res.splits.size()));
}

TEST(Crush, WithoutBreakageNothingBreaks) {
  CrushOptions o;
  o.breakage_on = false;
  o.final_travel_fraction = 0.05;
  const CrushResult res = run_crush(o);
  EXPECT_TRUE(res.splits.empty());
  EXPECT_EQ(res.final_record.spheres, 0);  // no model, no records
  ASSERT_FALSE(res.history.empty());
  EXPECT_GT(res.history.back().force_N, 0);
}

#include "dem/pluviation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "dem/time_step.hpp"

namespace tg::dem {
namespace {

// A Ø7 mm cell filled to 4 mm (~65 grains): small enough for a unit test.
PluviationOptions small_cell() {
  PluviationOptions o;
  o.cylinder_radius_m = 3.5e-3;
  o.generation_height_m = 10e-3;
  o.target_height_m = 4e-3;
  o.max_time_s = 0.5;
  return o;
}

// Grains with nothing under them: at rest under gravity a grain touches the
// floor or a grain whose centre is lower (the cylinder wall pushes sideways
// only: no support without friction), which carries its weight. A grain in flight, or touching only grains beside or above it,
// has none. Contacts within 1e-4 r of touching (resting overlaps under
// self-weight are ~5-30 nm, 1e-5 r; a grain at rest may vibrate off one by
// a few nm). Necessary, not sufficient, for rest (a frictionless grain can
// balance on an unstable perch): the restart checks below test rest itself.
// O(n^2).
int64_t unsupported_grains(const Particles& p) {
  int64_t bad = 0;
  for (int64_t i = 0; i < p.size(); ++i) {
    const double tol = 1e-4 * p.r[i];
    bool held = p.z[i] - p.r[i] < tol;  // on the floor
    for (int64_t j = 0; j < p.size() && !held; ++j)
      held = j != i && p.z[j] < p.z[i] &&
             std::hypot(p.x[i] - p.x[j], p.y[i] - p.y[j], p.z[i] - p.z[j]) < p.r[i] + p.r[j] + tol;
    if (!held) {
      std::printf("unsupported grain %lld at z %.4f mm\n", static_cast<long long>(i), p.z[i] * 1e3);
      ++bad;
    }
  }
  return bad;
}

// Bulk height of a packing: the height of its centre of volume, which a
// lone grain on top barely moves (the top of the highest grain, the
// specimen height the oedometer uses, is the most fragile measure there is).
double bulk_height(const Particles& p) {
  double vz = 0, v = 0;
  for (int64_t i = 0; i < p.size(); ++i) {
    vz += p.r[i] * p.r[i] * p.r[i] * p.z[i];
    v += p.r[i] * p.r[i] * p.r[i];
  }
  return vz / v;
}

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
  EXPECT_TRUE(r.settled);  // settled means: kinetic energy below the tolerance
  EXPECT_GT(r.porosity, 0.3);
  EXPECT_LT(r.porosity, 0.7);
  // At rest under gravity every grain stands on the floor or on a grain below
  // its centre (a grain in flight has nothing under it).
  EXPECT_EQ(unsupported_grains(r.particles), 0);
}

// Densification (issue 6): the same grains deposited without friction pack
// denser than with the study's μ = 0.5 (frictionless spheres cannot hold the
// arches that friction does), and both packings stay free of overlaps
// (settled overlaps are elastic, < 1e-3 r).
TEST(Pluviation, FrictionlessDepositionPacksDenserWithoutOverlap) {
  PluviationOptions o = small_cell();
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
  std::printf("deposit porosity: mu 0.5 %.4f, mu 0 %.4f\n", rough.deposit_porosity, smooth.deposit_porosity);
  EXPECT_LT(smooth.deposit_porosity, rough.deposit_porosity - 0.01);  // measured: 0.5744 vs 0.5304 (0.5733 vs 0.5470 before the 10 ms rest window)
}

// Pressing, seeds 1-8 (Release only, label slow: ~10 s a seed). The same
// grains (count, radii and seed kept: the grain volume (1 - n) H is kept
// while the target height changes) settle into the same deposit, which the
// platen presses a tenth of a grain diameter below its highest grain, holds
// until at rest, and releases. Checked:
//  * while the platen holds: no grain stands above the platen (target) by
//    more than the Hertz overlap of one grain carrying the whole 10 kPa cap,
//    (0.385 N / (4/3 E* sqrt(r)))^(2/3) = 2.4 um at r 0.68 mm: 3 um;
//  * after release, one-sided: the bulk height (the centre of volume) has
//    not risen above the free deposit's by a hundredth of a diameter
//    (pressing moves the few top grains only: measured -30 to +0.9 um over
//    seeds 1-8; a kick at release that launched grains would lift it by
//    more, and so would a loosened specimen);
//  * no unsupported grain (unsupported_grains above);
//  * the released packing is at rest: restarted from it with the
//    preparation's contact law, its kinetic energy stays below the rest
//    tolerance and no grain moves by a hundredth of a diameter over 100 ms
//    (the rearrangements below moved grains by 0.1-0.5 mm).
// Why a grain could rise out of a "settled" packing while the kinetic energy
// grew (issue 25, seeds 1, 2, 6 of this cell): not an engine defect. Traced
// with the engine's energies every 1 ms over 300 ms after release (seed 2,
// former rule): kinetic + gravitational + elastic energy never rose (largest
// 1-ms change 0, total -1.5e-8 J) while grain 55 rose 126 um and grain 22
// fell 277 um: frictionless grains creeping out of an unstable arrangement
// (the same with fused or single steps: Engine.RunGivesTheBitsOfSingleSteps).
// The preparation had called them settled at one check below 1e-9 J (seed 6:
// 3.7e-10 J and growing; grain 57 held only by grain 11 and the wall, six
// other grains out of contact or in flight). Hence pluviate's rest window
// (KE below the tolerance at every check over 10 ms) and, for this 65-grain
// cell, a tolerance of 1e-11 J: the study's 1e-9 J is for 910 grains
// (1.1e-12 J a grain); 7e-11 J (the same per grain) still let seed 1 creep
// 0.5 mm after release. Both chosen on seeds 1-8, the seeds asserted here
// (a rest criterion, not an accuracy figure). bench/dem/RESULTS.md has the runs.
TEST(Pluviation, PressesTheDepositDownToTheTargetHeight) {
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    PluviationOptions o = small_cell();
    o.seed = seed;
    o.kinetic_energy_tol_J = 1e-11;
    o.press_to_target_height = false;
    const PluviationResult free = pluviate(o, EngineOptions{});
    ASSERT_TRUE(free.settled);
    EXPECT_FALSE(free.pressed);
    EXPECT_EQ(free.height_m, free.deposit_height_m);

    PluviationOptions q = o;
    q.press_to_target_height = true;
    q.target_height_m = free.height_m - 0.1 * o.d50_m;
    q.target_porosity = 1 - (1 - o.target_porosity) * o.target_height_m / q.target_height_m;
    const PluviationResult pressed = pluviate(q, EngineOptions{});
    ASSERT_EQ(pressed.particles.size(), free.particles.size());
    for (int64_t i = 0; i < free.particles.size(); ++i) ASSERT_EQ(pressed.particles.r[i], free.particles.r[i]);
    EXPECT_EQ(pressed.deposit_height_m, free.height_m);  // same deposit, bit for bit
    EXPECT_TRUE(pressed.pressed);
    EXPECT_TRUE(pressed.settled);
    EXPECT_EQ(pressed.press_stop_stress_Pa, 0.0) << "stopped early";
    const Particles& p = pressed.particles;
    const double bulk_free = bulk_height(free.particles), bulk_pressed = bulk_height(p);
    std::printf("seed %llu: deposit %.4f mm (bulk %.4f), target %.4f, held %.4f, released %.4f mm (bulk %.4f)\n",
                (unsigned long long)seed, free.height_m * 1e3, bulk_free * 1e3, q.target_height_m * 1e3,
                pressed.held_height_m * 1e3, pressed.height_m * 1e3, bulk_pressed * 1e3);
    EXPECT_LE(pressed.held_height_m, q.target_height_m + 3e-6);
    EXPECT_GT(pressed.held_height_m, 0.0);
    EXPECT_LT(bulk_pressed, bulk_free + 0.01 * o.d50_m);
    EXPECT_EQ(unsupported_grains(p), 0);

    // At rest: restart from the packing with the preparation's contact law
    // (frictionless, bottom and cylinder walls, no platen).
    EngineOptions eo;
    eo.time_step = q.time_step_safety * critical_time_step(p, eo.material, {}).dt_critical;
    eo.friction = eo.walls.platen_friction = eo.walls.cylinder_friction = q.deposition_friction;
    eo.walls.bottom = eo.walls.cylinder = true;
    eo.walls.top = false;
    eo.walls.cylinder_radius = q.cylinder_radius_m;
    Engine e(p, eo);
    const int64_t ms = static_cast<int64_t>(1e-3 / eo.time_step);
    double ke_max = 0, moved = 0;
    for (int k = 0; k < 100; ++k) {
      e.run(ms);
      ke_max = std::max(ke_max, e.kinetic_energy());
    }
    for (int64_t i = 0; i < p.size(); ++i)
      moved = std::max(moved, std::hypot(e.particles().x[i] - p.x[i], e.particles().y[i] - p.y[i], e.particles().z[i] - p.z[i]));
    EXPECT_LT(ke_max, q.kinetic_energy_tol_J);
    EXPECT_LT(moved, 0.01 * o.d50_m);  // creep; a rearrangement moves grains 0.1-0.5 mm
    // No overlap beyond the elastic ones.
    double worst = 0;
    for (int64_t i = 0; i < p.size(); ++i)
      for (int64_t j = i + 1; j < p.size(); ++j)
        worst = std::max(worst, (p.r[i] + p.r[j] - std::hypot(p.x[i] - p.x[j], p.y[i] - p.y[j], p.z[i] - p.z[j])) /
                                    std::min(p.r[i], p.r[j]));
    EXPECT_LT(worst, 1e-3);
  }
}

// Regression (issue 25): with the study's tolerance (1e-9 J) and the rest
// window, the pressed specimen of seed 6, which the former one-check rule
// called settled with a grain perched on another and the wall (3.7e-10 J and
// growing; restarted, grains moved by 0.84 mm), does not rearrange:
// restarted with the preparation's contact law for 100 ms, the kinetic
// energy stays below the tolerance and no grain moves by 5 % of a diameter
// (68 um; a rearrangement moves grains 0.1-0.5 mm). What is left is creep
// of the frictionless packing, and it depends on the summation order of the
// forces: seeds 1-8 restarted moved their farthest grain 34, 33, 262, 27,
// 38, 4.5, 103, 46 um with the interleaved parts of 1620aa5 and 6.9, 255, 19, 27, 6.8,
// 44, 103, 89 um with contiguous parts (seeds 3 and 2 at ~1e-9 J and above
// rearrange: the rest window lowers that risk, it does not remove it).
TEST(Pluviation, PressedSpecimenIsAtRestWithTheStudysTolerance) {
  PluviationOptions o = small_cell();
  o.seed = 6;
  o.press_to_target_height = false;
  const PluviationResult free = pluviate(o, EngineOptions{});
  ASSERT_TRUE(free.settled);
  PluviationOptions q = o;
  q.press_to_target_height = true;
  q.target_height_m = free.height_m - 0.1 * o.d50_m;
  const PluviationResult pressed = pluviate(q, EngineOptions{});
  ASSERT_TRUE(pressed.settled);
  const Particles& p = pressed.particles;
  EngineOptions eo;
  eo.time_step = q.time_step_safety * critical_time_step(p, eo.material, {}).dt_critical;
  eo.friction = eo.walls.platen_friction = eo.walls.cylinder_friction = 0;
  eo.walls.top = false;
  eo.walls.cylinder_radius = q.cylinder_radius_m;
  Engine e(p, eo);
  double ke_max = 0, moved = 0;
  for (int k = 0; k < 100; ++k) {
    e.run(static_cast<int64_t>(1e-3 / eo.time_step));
    ke_max = std::max(ke_max, e.kinetic_energy());
  }
  for (int64_t i = 0; i < p.size(); ++i)
    moved = std::max(moved, std::hypot(e.particles().x[i] - p.x[i], e.particles().y[i] - p.y[i], e.particles().z[i] - p.z[i]));
  std::printf("seed 6 restarted: KE max %.3g J, largest displacement %.3g um\n", ke_max, moved * 1e6);
  EXPECT_LT(ke_max, q.kinetic_energy_tol_J);
  EXPECT_LT(moved, 0.05 * o.d50_m);
}

// A target the grains cannot reach without deforming (half the deposit's
// height) is not forced: pressing stops at the stress cap, and the
// specimen stays higher than the target, as reported.
TEST(Pluviation, PressingStopsAtTheStressCap) {
  PluviationOptions o;
  o.cylinder_radius_m = 3.5e-3;
  o.generation_height_m = 10e-3;
  o.target_height_m = 2e-3;   // ~30 grains
  o.target_porosity = 0.01;   // count for a near-solid 2 mm disc: ~2x the grains that fit below 2 mm
  o.max_time_s = 0.5;
  o.press_max_stress_Pa = 1e3;
  const PluviationResult r = pluviate(o, EngineOptions{});
  EXPECT_TRUE(r.pressed);
  EXPECT_GT(r.press_stop_stress_Pa, 1e3);
  EXPECT_GT(r.height_m, 1.5 * o.target_height_m);
}

}  // namespace
}  // namespace tg::dem

// The breakage model's open choices (issue 21), each a config key, each
// against a hand-computed value: damping that reaches the bonds (local
// damping of the total force, bond dashpots), which spheres may split, the
// bond radius rule, and the stable form of keeping sub-limit spheres.
#include <gtest/gtest.h>

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include <memory>
#include <numbers>

#include "core/config.hpp"
#include "dem/breakage/breakage.hpp"
#include "dem/oedometer.hpp"
#include "dem/packing_io.hpp"
#include "dem/pluviation.hpp"

namespace tg::dem::breakage {
namespace {

constexpr double kDensity = 2180;  // kg/m^3, Table 1

constexpr double kPi = std::numbers::pi;

// Two 0.1 mm spheres bonded end to end along z, A fixed above B, in free
// space; gravity (a step load m g switched on at t = 0, from rest) pulls B
// down and stretches the bond. B moves along z only: a one-degree-of-freedom
// oscillator of stiffness k = k̄n A_bond (the contact never closes: the
// spheres start tangent and separate). Returns the bond tension at B's
// first turning point (its largest) divided by the static one, m g.
double step_load_overshoot(double alpha, bool total, double beta) {
  const double r = 1e-4;
  Particles p;
  p.append_sphere(0, 0, 0, r, kDensity, 0, 0, kFlagFixed);
  p.append_sphere(0, 0, -2 * r, r, kDensity, 1, 0, kFlagNone);
  const double m = p.m[1];
  EngineOptions o;
  o.walls.bottom = o.walls.top = o.walls.cylinder = false;
  o.local_damping = alpha;
  o.local_damping_total = total;
  BreakageOptions b;
  b.strength.d0_m = 1e-3;
  b.bond.damping_ratio = beta;
  // Period of the undamped oscillator: 2π √(m/k); 4000 steps a period.
  const BondSection sec = bond_section(b.bond, r, r);
  const double period = 2 * kPi * std::sqrt(m / (sec.kn * sec.area));
  o.time_step = period / 4000;
  Engine eng(std::move(p), o);
  BreakageModel model(eng, b);
  model.add_bond(0, 1);
  double peak = 0;
  for (int k = 0; k < 8000; ++k) {
    eng.step();
    peak = std::max(peak, -model.bond_state(0).fn);  // tension: fn < 0
    if (k > 10 && eng.particles().vz[1] >= 0) break;  // turned
  }
  return peak / (m * -o.gravity_z);
}

// Today (issue 21, lead 1): the bond force is added after the damped
// gather, so a bond under a step load overshoots 2.0x undamped, and local
// damping α only damps the load (gravity, (1 − α) m g while B falls), not
// the bond: the first swing peaks at 2 (1 − α) (after it B creeps on, as
// the damped load depends on the sign of its velocity).
TEST(BreakageOptions, StepLoadOnABondOvershootsTwiceWhenTheBondIsUndamped) {
  EXPECT_NEAR(step_load_overshoot(0, false, 0), 2.0, 2e-3);
  EXPECT_NEAR(step_load_overshoot(0.7, false, 0), 2 * (1 - 0.7), 2e-3);
}

// Local damping of the total force: while B moves down the net force
// F = m g − k u is scaled by (1 − α) until u = m g/k, then by (1 + α) on
// the way to the peak; equating work and kinetic energy, the overshoot past
// the static stretch is √((1 − α)/(1 + α)) of it: 1.4201 for α = 0.7 (the
// issue's 1.42x), 1.8165 for α = 0.1.
TEST(BreakageOptions, LocalDampingOfTheTotalForceReachesTheBond) {
  for (double alpha : {0.1, 0.7}) {
    const double expected = 1 + std::sqrt((1 - alpha) / (1 + alpha));
    EXPECT_NEAR(step_load_overshoot(alpha, true, 0), expected, 2e-3) << "alpha " << alpha;
  }
}

// Bond dashpot: c = 2β√(m* k) with m* = m/2 (two equal masses), acting on
// B alone (A is fixed), so B's damping ratio is ζ = c/(2√(m k)) = β/√2 and
// the step response peaks at 1 + exp(−πζ/√(1 − ζ²)) (a damped oscillator):
// β = 0.2 → ζ = 0.14142, 1.6392; β = 0.5 → ζ = 0.35355, 1.3051.
TEST(BreakageOptions, BondDashpotGivesTheDampedOscillatorsOvershoot) {
  for (double beta : {0.2, 0.5}) {
    const double zeta = beta / std::sqrt(2.0);
    const double expected = 1 + std::exp(-kPi * zeta / std::sqrt(1 - zeta * zeta));
    EXPECT_NEAR(step_load_overshoot(0, false, beta), expected, 2e-3) << "beta " << beta;
  }
  EXPECT_NEAR(1 + std::exp(-kPi * 0.5 / std::sqrt(2.0) / std::sqrt(1 - 0.125)), 1.3051, 1e-4);  // the value quoted
}

// Bond radius: the study's λ (RA + RB)/2 or PFC's λ min(RA, RB). For
// 0.1 mm and 0.05 mm spheres, λ = 1.25: 93.75 µm or 62.5 µm; area π R̄²,
// I = π R̄⁴/4; the stiffness per area k̄n = E/(RA + RB) is the same.
TEST(BreakageOptions, BondRadiusRuleMeanOrMin) {
  ParallelBondParams p;
  const BondSection mean = bond_section(p, 1e-4, 0.5e-4);
  p.radius_rule = BondRadiusRule::kMin;
  const BondSection min = bond_section(p, 1e-4, 0.5e-4);
  EXPECT_DOUBLE_EQ(mean.radius, 93.75e-6);
  EXPECT_DOUBLE_EQ(min.radius, 62.5e-6);
  EXPECT_NEAR(min.area, kPi * 62.5e-6 * 62.5e-6, 1e-12 * min.area);
  EXPECT_NEAR(min.inertia, kPi * std::pow(62.5e-6, 4) / 4, 1e-12 * min.inertia);
  EXPECT_DOUBLE_EQ(min.kn, 5.5e9 / 1.5e-4);
  EXPECT_DOUBLE_EQ(mean.kn, min.kn);
  // Equal spheres: the two rules agree.
  EXPECT_DOUBLE_EQ(bond_section(p, 1e-4, 1e-4).radius, 1.25e-4);
}

// The three 1 mm spheres of the two tests below: A sunk `a_sink_m` into the
// bottom platen, B beside it, C alone; B and C sunk 1 µm, the top platen 1 µm
// into each.
struct ThreeSpheres {
  Particles p;
  EngineOptions o;
  BreakageOptions b;
  explicit ThreeSpheres(double a_sink_m = 1e-6) {
    const double d = 1e-3, r = d / 2, delta = 1e-6;
    p.append_sphere(0, 0, r - a_sink_m, r, kDensity, 0);   // A
    p.append_sphere(d, 0, r - delta, r, kDensity, 1);      // B, tangent to A
    p.append_sphere(4 * d, 0, r - delta, r, kDensity, 2);  // C, alone
    o.gravity_z = 0;
    o.walls.cylinder = false;
    o.walls.top_z = d - 2 * delta;
    o.time_step = 1e-9;
    b.strength.d0_m = 1e-3;
    b.strength.sigma_t0_Pa = 1e3;
  }
};

// Which spheres may split. Three 1 mm spheres on the bottom platen, pressed
// 1 µm into each platen by the top one (F ≈ 0.087 N each, F/d² ≈ 87 kPa,
// far above strengths drawn with σt0 = 1 kPa): A and B side by side and
// bonded, C alone. split_bonded = true splits all three; false only C.
TEST(BreakageOptions, SplitBondedFalseSplitsOnlySpheresWithoutBonds) {
  const double d = 1e-3;
  for (bool split_bonded : {true, false}) {
    ThreeSpheres t;
    Engine eng(std::move(t.p), t.o);
    BreakageOptions b = t.b;
    b.split_bonded = split_bonded;
    BreakageModel model(eng, b);
    model.add_bond(0, 1);
    eng.step();
    for (int64_t s = 0; s < 3; ++s) ASSERT_GT(model.max_normal_forces()[s] / (d * d), 10 * model.strength(s));
    model.check();
    if (split_bonded) {
      EXPECT_EQ(model.record().grains_broken, 3);
      ASSERT_EQ(model.events().size(), 3u);
    } else {
      EXPECT_EQ(model.record().grains_broken, 1);
      ASSERT_EQ(model.events().size(), 1u);
      EXPECT_EQ(model.events()[0].sphere, 2);  // C
      EXPECT_EQ(model.bond_count(), 1 + 2 * 40);  // A–B and C's two fragments
    }
  }
}

// ... except a bonded sphere squeezed past fines_overlap × r: nothing else
// stops it being pushed through (its bonds carry only compression there).
// A, bonded to B, sits in the bottom platen by 0.29 r (kept whole) or 0.31 r
// (split, its bond to B dropped with it: only the fragments' 2 × 40 bonds of
// each split remain); B, bonded and pressed by 1 µm, never splits; C, alone,
// always does.
TEST(BreakageOptions, SplitBondedFalseSplitsABondedSphereSqueezedPastFinesOverlap) {
  const double d = 1e-3;
  for (double squeeze : {0.29, 0.31}) {
    ThreeSpheres t(squeeze * d / 2);
    Engine eng(std::move(t.p), t.o);
    BreakageOptions b = t.b;
    b.split_bonded = false;
    b.sublimit = SublimitPolicy::kKeep;  // no fines: A's fragment spheres are born deep in the platen
    ASSERT_DOUBLE_EQ(b.fines_overlap, 0.3);
    BreakageModel model(eng, b);
    model.add_bond(0, 1);
    eng.step();
    for (int64_t s = 0; s < 3; ++s) ASSERT_GT(model.max_normal_forces()[s] / (d * d), 10 * model.strength(s));
    model.check();
    if (squeeze < 0.3) {
      ASSERT_EQ(model.events().size(), 1u);
      EXPECT_EQ(model.events()[0].sphere, 2);       // C
      EXPECT_EQ(model.bond_count(), 1 + 2 * 40);    // A–B and C's fragments
    } else {
      ASSERT_EQ(model.events().size(), 2u);
      EXPECT_EQ(model.events()[0].sphere, 0);       // A
      EXPECT_EQ(model.events()[1].sphere, 2);       // C
      EXPECT_EQ(model.bond_count(), 2 * 2 * 40);    // A–B went with A
      EXPECT_EQ(model.record().bonds_dropped, 1);
      EXPECT_EQ(model.record().bonds_broken, 0);
    }
  }
}

// kKeepUnbreakable, the stable form of kKeep: a 0.15 mm sphere pressed by
// the top platen onto a large unbreakable sphere is kept past its strength
// (the study: sub-limit spheres do not break) and removed only when its
// overlap passes fines_overlap = 0.3 r, before the engine's 0.5 r limit
// stops the run (what kKeep does: BreakageModel.SubLimitSpherePushed...).
TEST(BreakageOptions, KeepUnbreakableKeepsSubLimitSpheresUntilSqueezed) {
  const double R = 0.5e-3, r = 0.075e-3;
  Particles p;
  p.append_sphere(0, 0, R, R, kDensity, 0, 0, kFlagNone);
  p.append_sphere(0, 0, 2 * R + r, r, kDensity, 1);
  EngineOptions o;
  o.gravity_z = 0;
  o.walls.cylinder = false;
  o.walls.top_z = 2 * R + 2 * r;
  o.walls.top_vz = -0.5;
  o.time_step = 2e-9;
  o.skin = 2e-5;
  Engine eng(std::move(p), o);
  BreakageOptions b;
  b.strength.d0_m = 1e-3;
  b.sublimit = SublimitPolicy::kKeepUnbreakable;
  BreakageModel model(eng, b);
  const double strength = model.strength(1);
  double overlap_prev = 0, sigma_max = 0;
  for (int k = 0; k < 100000 && eng.particles().size() == 2; ++k) {
    eng.run(10);
    const Particles& q = eng.particles();
    const double o_ratio = std::max(R + r - (q.z[1] - q.z[0]), q.z[1] + r - eng.walls().top_z) / r;
    sigma_max = std::max(sigma_max, model.max_normal_forces()[1] / (4 * r * r));
    model.check();
    if (eng.particles().size() == 2) overlap_prev = o_ratio;
  }
  ASSERT_EQ(eng.particles().size(), 1);
  EXPECT_GT(sigma_max, strength);  // kept past its strength (kRemove removes it at the crossing)
  EXPECT_LE(overlap_prev, 0.3);
  EXPECT_GT(overlap_prev, 0.28);
  EXPECT_EQ(model.record().fines_removed, 1);
  EXPECT_EQ(model.record().grains_broken, 0);
}

// Every new option on at once (damping of the total force, bond dashpots,
// no splitting of bonded spheres, sub-limit spheres kept unbreakable, PFC's
// bond radius), weak grains so that grains split early: a run stopped and
// restarted from its checkpoint ends bit for bit where the uninterrupted one
// does, and 2 threads give the 1-thread bits. None of the options adds state
// to the checkpoint (they are config keys, read again on restart). With
// birth_overlap "mother" (shrunk spheres, bonds sized from their radii) and
// the log of broken bonds: the log of the restarted run (before + after the
// restart) has the uninterrupted run's rows, ages included (the bonds' birth
// steps travel in the checkpoint).
TEST(BreakageOptions, NewOptionsKeepRestartAndThreadsBitExact) {
  namespace fs = std::filesystem;
  const fs::path d = fs::temp_directory_path() / ("tg_brk_opts_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  PluviationOptions po;
  po.cylinder_radius_m = 3e-3;
  po.generation_height_m = 6e-3;
  po.target_height_m = 3e-3;
  write_packing_csv(insert_grains(po, 2180), d / "packing.csv");
  auto setup = [&](int threads) {
    Config cfg = Config::from_string(
        "[contact]\nlocal_damping = 0.7\nlocal_damping_scope = \"total\"\n"
        "[walls]\ncylinder_radius_m = 3e-3\nplaten_friction = 0.0\ncylinder_friction = 0.0\n"
        "[run]\nthreads = " + std::to_string(threads) + "\nparallel_min_items = 0\n"
        "[specimen]\npacking_csv = \"packing.csv\"\n"
        "[oedometer]\nplaten_speed_m_s = 0.5\ntarget_strain = 0.05\nsnapshot_strains = [0.0, 0.05]\n"
        "history_every_steps = 200\ncheckpoint_every_steps = 1000\n"
        "[breakage]\nsigma_t0_Pa = 1.0e6\nmin_split_diameter_m = 5.0e-4\nbond_damping = 0.5\nsplit_bonded = false\n"
        "sublimit_policy = \"keep_unbreakable\"\nbond_radius_rule = \"min\"\nbirth_overlap = \"mother\"\n"
        "log_bond_breaks = true\n",
        "options.toml");
    return read_oedometer_config(cfg, d);
  };
  RunControl full;
  full.quiet = true;
  const OedometerSummary a = run_oedometer(setup(1), d / "a", full);
  ASSERT_TRUE(a.finished);
  ASSERT_GT(a.breakage.grains_broken, 0);  // the options were exercised
  ASSERT_GT(a.breakage.bonds_intact, 0);
  RunControl part = full;
  part.stop_after_steps = a.steps / 2 + 7;  // not on a checkpoint/history boundary
  EXPECT_FALSE(run_oedometer(setup(1), d / "b", part).finished);
  RunControl resume = full;
  resume.restart = true;
  const OedometerSummary b = run_oedometer(setup(1), d / "b", resume);
  const OedometerSummary c = run_oedometer(setup(2), d / "c", full);
  for (const OedometerSummary* o : {&b, &c}) {
    EXPECT_EQ(o->steps, a.steps);
    EXPECT_EQ(o->top_stress_Pa, a.top_stress_Pa);
    EXPECT_EQ(o->breakage.bonds_broken, a.breakage.bonds_broken);
    EXPECT_TRUE(o->final_state.x == a.final_state.x && o->final_state.vz == a.final_state.vz &&
                o->final_state.wx == a.final_state.wx);
  }
  auto rows = [](const fs::path& f) {
    std::ifstream in(f);
    std::vector<std::string> r;
    for (std::string line; std::getline(in, line);) r.push_back(line);
    if (!r.empty()) r.erase(r.begin());  // header
    return r;
  };
  const std::vector<std::string> log_a = rows(d / "a" / "bond_breaks.csv");
  ASSERT_GT(log_a.size(), 0u);
  EXPECT_EQ(rows(d / "c" / "bond_breaks.csv"), log_a);
  std::vector<std::string> log_b = rows(d / "b" / "bond_breaks.csv");
  for (const std::string& line : rows(d / "b" / "bond_breaks_after_restart.csv")) log_b.push_back(line);
  EXPECT_EQ(log_b, log_a);
  fs::remove_all(d);
}

}  // namespace
}  // namespace tg::dem::breakage

// BreakageModel: selective density scaling of new spheres and the removal of
// sub-limit spheres as fines (the two modelling decisions of
// dem/breakage/README.md, "Time step and sub-limit spheres").
#include "dem/breakage/breakage.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <utility>

namespace tg::dem::breakage {
namespace {

constexpr double kRho = 2180;

double sphere_volume(double r) { return 4.0 / 3.0 * std::numbers::pi * r * r * r; }

// Platens only, no gravity, no cylinder: the crush scene's walls.
EngineOptions platens(double top_z, double dt) {
  EngineOptions o;
  o.gravity_z = 0;
  o.walls.cylinder = false;
  o.walls.top_z = top_z;
  o.walls.top_vz = -0.1;
  o.time_step = dt;
  o.skin = 2e-5;
  return o;
}

BreakageOptions options(double min_dt) {
  BreakageOptions b;
  b.strength.d0_m = 1e-3;
  b.min_time_step_s = min_dt;
  return b;
}

// One grain of diameter d crushed between the platens until its first split.
struct Crushed {
  std::unique_ptr<Engine> eng;
  std::unique_ptr<BreakageModel> model;
};
Crushed crush_until_split(double d, const BreakageOptions& b) {
  Particles p;
  p.append_sphere(0, 0, d / 2, d / 2, kRho, 0);
  Crushed c;
  // Grain step: ~0.1 of its own Hertz step (1.2 mm: 1.1e-7 s), above the minimum.
  c.eng = std::make_unique<Engine>(std::move(p), platens(d, 2e-8 * d / 0.22e-3));
  c.model = std::make_unique<BreakageModel>(*c.eng, b);
  while (c.model->events().empty()) c.model->run(b.check_interval);
  return c;
}

// A split of a 0.22 mm element makes 35–98 µm spheres whose own critical
// steps (bending of their bonds) are 4–16 ns: with min_time_step 1e-8 s and
// safety 0.5 they are scaled up to exactly 2e-8 s and the run's step stays
// at 1e-8 s. The added mass is checked against an independent count: the
// nominal mass is ρ Σ 4/3 π r³ over the spheres.
TEST(BreakageModel, DensityScalingLiftsTheStepToTheMinimum) {
  BreakageOptions b = options(1e-8);
  b.sublimit = SublimitPolicy::kKeep;  // all 34 spheres (see the next test)
  Crushed c = crush_until_split(0.22e-3, b);
  const Particles& p = c.eng->particles();
  ASSERT_EQ(p.size(), 34);
  EXPECT_GE(c.eng->options().time_step, 1e-8);
  EXPECT_LE(c.eng->options().time_step, 1e-8 * (1 + 1e-6));
  double nominal = 0, total = 0, max_factor = 1;
  int scaled = 0;
  for (int64_t s = 0; s < p.size(); ++s) {
    const double m0 = kRho * sphere_volume(p.r[s]);
    nominal += m0;
    total += p.m[s];
    EXPECT_NEAR(p.m[s] / m0, c.model->mass_factor(s), 1e-9 * c.model->mass_factor(s));
    EXPECT_NEAR(p.inertia[s], 0.4 * p.m[s] * p.r[s] * p.r[s], 1e-9 * p.inertia[s]);  // I scaled alike
    scaled += c.model->mass_factor(s) > 1;
    max_factor = std::max(max_factor, c.model->mass_factor(s));
  }
  EXPECT_GT(scaled, 0);
  EXPECT_LT(max_factor, 30.0);  // the ring-B spheres: (2e-8 / 4.3e-9)² ≈ 21
  EXPECT_NEAR(c.model->record().added_mass_kg, total - nominal, 1e-9 * nominal);
  EXPECT_NEAR(c.model->record().added_mass_fraction, (total - nominal) / nominal, 1e-9);
  // Without scaling the same split drops the step to ~2 ns.
  Crushed ref = crush_until_split(0.22e-3, options(0));
  EXPECT_LT(ref.eng->options().time_step, 0.3e-8);
  EXPECT_EQ(ref.model->record().added_mass_kg, 0.0);
  // The split itself is the same (density scaling acts only on new spheres).
  EXPECT_EQ(ref.model->events().front().step, c.model->events().front().step);
  EXPECT_EQ(ref.model->events().front().f_max_N, c.model->events().front().f_max_N);
}

// The same split with kRemove: the fragment spheres born overlapping a
// platen by more than fines_overlap × their radius (the mother pressed
// ~15 µm into each platen: a small sphere there starts deep in the platen)
// are removed at once as fines; counted from the geometry of the
// kKeep split (independent of the removal code).
TEST(BreakageModel, FragmentSpheresBornDeepInAContactAreFines) {
  BreakageOptions keep = options(1e-8);
  keep.sublimit = SublimitPolicy::kKeep;
  Crushed k = crush_until_split(0.22e-3, keep);
  const Particles& q = k.eng->particles();
  int deep = 0;
  double v_deep = 0;
  for (int64_t s = 0; s < q.size(); ++s) {
    const double o = std::max(q.r[s] - q.z[s], q.z[s] + q.r[s] - k.eng->walls().top_z);
    if (o > 0.3 * q.r[s]) {
      ++deep;
      v_deep += sphere_volume(q.r[s]);
    }
  }
  ASSERT_GT(deep, 0);
  Crushed c = crush_until_split(0.22e-3, options(1e-8));
  EXPECT_EQ(c.eng->particles().size(), 34 - deep);
  EXPECT_EQ(c.model->record().fines_removed, deep);
  EXPECT_NEAR(c.model->record().fines_volume_m3, v_deep, 1e-9 * v_deep);
  c.model->run(2000);  // and the run goes on without them
}

// Removing a fragment element renumbers the spheres after it; every
// surviving bond, strength and position must follow its sphere.
TEST(BreakageModel, RemovingFinesRenumbersBondsAndKeepsStrengths) {
  Crushed c = crush_until_split(1.2e-3, options(1e-8));
  const Particles& p = c.eng->particles();
  ASSERT_EQ(p.size(), 34);
  using Key = std::array<double, 3>;
  auto key = [&](int64_t s) { return Key{p.x[s], p.y[s], p.z[s]}; };  // identity by position
  std::map<Key, double> strength;
  for (int64_t s = 0; s < p.size(); ++s) strength[key(s)] = c.model->strength(s);
  std::set<std::pair<Key, Key>> bonds;
  const int64_t gone = 12;  // a ring-B element of fragment 0 (degree 3)
  int degree = 0;
  for (int64_t k = 0; k < c.model->bond_count(); ++k) {
    const int64_t a = c.model->bond_a(k), b = c.model->bond_b(k);
    if (a == gone || b == gone) {
      ++degree;
      continue;
    }
    bonds.insert({key(a), key(b)});
  }
  ASSERT_GT(degree, 0);
  const double r_gone = p.r[gone];
  const BreakageRecord before = c.model->record();
  c.model->remove_fines({gone});
  const BreakageRecord& after = c.model->record();
  ASSERT_EQ(p.size(), 33);
  EXPECT_EQ(after.fines_removed, 1);
  EXPECT_DOUBLE_EQ(after.fines_volume_m3, sphere_volume(r_gone));
  EXPECT_NEAR(after.volume_lost_m3 - before.volume_lost_m3, sphere_volume(r_gone), 1e-9 * sphere_volume(r_gone));
  EXPECT_EQ(after.bonds_dropped - before.bonds_dropped, degree);
  EXPECT_EQ(after.spheres, 33);
  EXPECT_EQ(c.model->bond_count(), static_cast<int64_t>(bonds.size()));
  for (int64_t k = 0; k < c.model->bond_count(); ++k) {
    const int64_t a = c.model->bond_a(k), b = c.model->bond_b(k);
    EXPECT_LT(a, b);
    EXPECT_TRUE(bonds.count({key(a), key(b)})) << "bond " << a << "-" << b << " is not one of the old bonds";
    EXPECT_NEAR(std::hypot(p.x[b] - p.x[a], p.y[b] - p.y[a], p.z[b] - p.z[a]), p.r[a] + p.r[b], 1e-6 * p.r[a]);
  }
  for (int64_t s = 0; s < p.size(); ++s) EXPECT_EQ(c.model->strength(s), strength.at(key(s)));
  EXPECT_EQ(after.particles, 2);  // a ring-B sphere is not a cut vertex of its fragment
  c.model->run(200);              // and the run goes on
  EXPECT_EQ(p.size(), 33);
}

// A 0.15 mm sphere (below the 0.2 mm limit) pressed by the top platen onto a
// large unbreakable sphere: with kRemove it is removed at the first check
// where F_max/d² exceeds its strength; with kKeep it stays and is pushed on.
struct Pinch {
  std::unique_ptr<Engine> eng;
  std::unique_ptr<BreakageModel> model;
  double small_strength = 0;
};
Pinch pinch(SublimitPolicy policy, double sigma_t0) {
  const double R = 0.5e-3, r = 0.075e-3;
  Particles p;
  p.append_sphere(0, 0, R, R, kRho, 0, 0, kFlagNone);  // not breakable
  p.append_sphere(0, 0, 2 * R + r, r, kRho, 1);
  Pinch c;
  EngineOptions o = platens(2 * R + 2 * r, 2e-9);
  o.walls.top_vz = -0.5;  // still ~10⁴ checks before the small sphere gives way
  c.eng = std::make_unique<Engine>(std::move(p), o);
  BreakageOptions b = options(1e-8);
  b.sublimit = policy;
  b.strength.sigma_t0_Pa = sigma_t0;
  c.model = std::make_unique<BreakageModel>(*c.eng, b);
  c.small_strength = c.model->strength(1);
  return c;
}

TEST(BreakageModel, SubLimitSphereOverItsStrengthIsRemovedAsFines) {
  Pinch c = pinch(SublimitPolicy::kRemove, 12e6);
  const double d = 0.15e-3;
  double sigma_prev = 0, sigma_at = 0;
  for (int k = 0; k < 100000 && c.eng->particles().size() == 2; ++k) {
    c.eng->run(10);
    const double sigma = c.model->max_normal_forces()[1] / (d * d);
    c.model->check();
    if (c.eng->particles().size() == 1) sigma_at = sigma;
    else sigma_prev = sigma;
  }
  ASSERT_EQ(c.eng->particles().size(), 1);
  EXPECT_GT(sigma_at, c.small_strength);
  EXPECT_LE(sigma_prev, c.small_strength);
  EXPECT_GT(sigma_prev, 0.9 * c.small_strength);  // loaded gradually: removed at the crossing
  const BreakageRecord& r = c.model->record();
  EXPECT_EQ(r.fines_removed, 1);
  EXPECT_EQ(r.grains_broken, 0);
  EXPECT_DOUBLE_EQ(r.fines_volume_m3, sphere_volume(0.5 * d));
  EXPECT_DOUBLE_EQ(c.eng->particles().r[0], 0.5e-3);  // the large sphere is untouched
}

// Too strong to meet the criterion: removed when its overlap passes
// fines_overlap (0.3 r), i.e. before the engine's 0.5 r limit. kKeep leaves
// it in and the engine's overlap limit stops the run.
TEST(BreakageModel, SubLimitSpherePushedIntoANeighbourIsRemovedOrStopsTheRun) {
  Pinch c = pinch(SublimitPolicy::kRemove, 1e15);
  const double r = 0.075e-3;
  double overlap_prev = 0;
  for (int k = 0; k < 100000 && c.eng->particles().size() == 2; ++k) {
    c.eng->run(10);
    const Particles& p = c.eng->particles();
    const double o = std::max(0.5e-3 + r - (p.z[1] - p.z[0]), p.z[1] + r - c.eng->walls().top_z) / r;
    c.model->check();
    if (c.eng->particles().size() == 2) overlap_prev = o;
  }
  ASSERT_EQ(c.eng->particles().size(), 1);
  EXPECT_LE(overlap_prev, 0.3);
  EXPECT_GT(overlap_prev, 0.28);
  EXPECT_EQ(c.model->record().fines_removed, 1);

  Pinch keep = pinch(SublimitPolicy::kKeep, 1e15);
  EXPECT_THROW(
      for (int k = 0; k < 100000; ++k) {
        keep.eng->run(10);
        keep.model->check();
      },
      SimulationError);
  EXPECT_EQ(keep.eng->particles().size(), 2);
  EXPECT_EQ(keep.model->record().fines_removed, 0);
}


// A sub-limit sphere shot into a neighbour or a wall so fast that it passes
// the engine's overlap limit (0.5 of the smaller radius) between two checks
// (fragment spheres of a violent split: two 25 um spheres met at 93 m/s in a
// calibration's crush test, 0.09 -> 0.52 r in 7 steps of a 10-step check
// interval). The rule of check() (squeezed past fines_overlap: fines) holds
// there too: the sphere is removed at once, by a check right after that
// step, and the run goes on; kKeep, and spheres large enough to split, still
// stop the run as unstable.
struct Shot {
  std::unique_ptr<Engine> eng;
  std::unique_ptr<BreakageModel> model;
};
// Sphere 1 (radius r1, breakable) flies at `speed` along -z onto sphere 0
// (radius r0, not breakable) or, with r0 = 0, onto the bottom platen.
Shot shoot(double r0, double r1, double speed, SublimitPolicy policy) {
  Particles p;
  const double z0 = r0 > 0 ? 0.5e-3 : 0.0;  // 0.15 mm of flight either way
  if (r0 > 0) p.append_sphere(0, 0, z0, r0, kRho, 0, 0, kFlagNone);
  p.append_sphere(0, 0, z0 + r0 + r1 + 0.15e-3, r1, kRho, 1);
  p.vz.back() = -speed;
  Shot c;
  c.eng = std::make_unique<Engine>(std::move(p), platens(2e-3, 1e-9));
  BreakageOptions b = options(0);
  b.sublimit = policy;
  b.check_interval = 1000;  // the flight and the impact fall between two checks
  b.strength.sigma_t0_Pa = 1e15;
  c.model = std::make_unique<BreakageModel>(*c.eng, b);
  return c;
}

TEST(BreakageModel, SubLimitSphereShotPastTheOverlapLimitIsFinesNotAnUnstableRun) {
  const double r = 25e-6, R = 0.5e-3;
  for (const SublimitPolicy policy : {SublimitPolicy::kRemove, SublimitPolicy::kKeepUnbreakable}) {
    // Onto a large sphere: 800 m/s would take a Hertz contact of these
    // radii to ~1 r of overlap (energy balance); the limit is 0.5 r.
    Shot c = shoot(R, r, 800, policy);
    c.model->run(500);  // impact after ~190 steps; no interval check before step 1000
    ASSERT_EQ(c.eng->particles().size(), 1);
    EXPECT_EQ(c.model->record().fines_removed, 1);
    EXPECT_DOUBLE_EQ(c.model->record().fines_volume_m3, sphere_volume(r));
    EXPECT_DOUBLE_EQ(c.eng->particles().r[0], R);  // the large sphere stays
    // Onto the bottom platen.
    Shot w = shoot(0, r, 800, policy);
    w.model->run(500);
    EXPECT_EQ(w.eng->particles().size(), 0);
    EXPECT_EQ(w.model->record().fines_removed, 1);
    w.model->run(100);  // and the run goes on
  }
  // kKeep: no sphere is ever fines, the run stops as before.
  Shot keep = shoot(R, r, 800, SublimitPolicy::kKeep);
  EXPECT_THROW(keep.model->run(500), SimulationError);
  // A sphere large enough to split (0.3 mm > 0.2 mm) is not fines: stopped.
  Shot big = shoot(R, 0.15e-3, 2000, SublimitPolicy::kRemove);
  EXPECT_THROW(big.model->run(500), SimulationError);
}

}  // namespace
}  // namespace tg::dem::breakage

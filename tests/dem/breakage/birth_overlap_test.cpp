// Fragments born loaded (issue 21, frag21): the birth figures of a split
// (overlaps of the mother and of her new spheres, Hertz force at birth), the
// birth_overlap remedies that shrink new spheres, and the log of broken
// bonds with their ages — each against a hand-computed value.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "dem/breakage/breakage.hpp"
#include "dem/breakage/fragment_template.hpp"

namespace tg::dem::breakage {
namespace {

constexpr double kBirthRho = 2180;  // kg/m^3, Table 1

// One 1 mm sphere pinched between two fixed platens, each overlapping it by
// 0.1 R; very weak (σt0 1 kPa), so the first check splits it. Contacts along
// z only, so the splitting plane contains z (fixed-axis rule) and ex = ±z:
// the ring-A spheres at azimuth 0° and 180° of both fragments point at the
// platens. Their outer point lies ρA + ra = 0.951340 R from the centre, so
// each of these 4 spheres overlaps a platen by o = ρA + ra − 0.9 = 0.051340 R
// (o/r = 0.19499 > 0.1, under the fines limit 0.3); no other new sphere
// reaches a platen (ring B: 0.548 + 0.161 R, A at 45°: 0.486 + 0.263 R).
struct BirthPinch {
  static constexpr double R = 0.5e-3, q = 0.1;
  Particles p;
  EngineOptions o;
  BreakageOptions b;
  explicit BirthPinch(BirthOverlap birth) {
    p.append_sphere(0, 0, R - q * R, R, kBirthRho, 0);
    o.gravity_z = 0;
    o.walls.cylinder = false;
    o.walls.top_z = 2 * R - 2 * q * R;
    o.time_step = 1e-10;
    b.strength.d0_m = 1e-3;
    b.strength.sigma_t0_Pa = 1e3;
    b.birth_overlap = birth;
    b.min_time_step_s = 0;  // nominal masses (no density scaling)
  }
};

// Largest platen overlap of sphere s, m.
double birth_platen_overlap(Engine& e, int64_t s) {
  const Particles& p = e.particles();
  return std::max(p.r[s] - p.z[s], p.z[s] + p.r[s] - e.walls().top_z);
}

TEST(BirthOverlap, InheritKeepsTheTemplateAndReportsTheOverlaps) {
  BirthPinch c(BirthOverlap::kInherit);
  Engine eng(std::move(c.p), c.o);
  BreakageModel model(eng, c.b);
  eng.step();
  const double lost_before = model.record().volume_lost_m3;
  ASSERT_EQ(model.check(), 1);
  const FragmentTemplate& t = fragment_template();
  const double R = BirthPinch::R;
  const double o = (std::sqrt(1 - 2 * t.ra) + t.ra - 0.9) * R;  // ρA + ra − 0.9, in R
  EXPECT_NEAR(o / R, 0.051340, 1e-6);
  const SplitEvent& ev = model.events().at(0);
  EXPECT_NEAR(ev.mother_overlap_ratio, 0.1, 1e-9);
  EXPECT_NEAR(ev.fragment_overlap_ratio, o / (t.ra * R), 1e-9);
  EXPECT_EQ(ev.fragment_contacts, 4);
  // Hertz, sphere on a rigid-equivalent platen of the same material:
  // E* = E / (2 (1 − ν²)), r_eff = r.
  const double e_star = 5.5e9 / (2 * (1 - 0.25 * 0.25));
  const double r = t.ra * R;
  EXPECT_NEAR(ev.fragment_force_N, 4.0 / 3.0 * e_star * std::sqrt(r) * std::pow(o, 1.5), 1e-9 * ev.fragment_force_N);
  int touching = 0;
  for (int64_t s = 0; s < eng.particles().size(); ++s) {
    const double x = eng.particles().r[s] / R;  // a template radius, unshrunk
    EXPECT_TRUE(std::abs(x - t.rc) < 1e-12 || std::abs(x - t.ra) < 1e-12 || std::abs(x - t.rb) < 1e-12) << x;
    if (birth_platen_overlap(eng, s) > 0) ++touching;
  }
  EXPECT_EQ(touching, 4);
  const double mother = 4.0 / 3.0 * std::numbers::pi * R * R * R;
  EXPECT_NEAR(model.record().volume_lost_m3 - lost_before, mother * (1 - t.retained_fraction()), 1e-12 * mother);
}

// kNone: the 4 spheres are shrunk by o (centre kept) and only touch; the
// shaved volume 4 · 4/3 π (ra³ − (ra − o)³) R³ joins the volume lost.
// kMotherRatio: shrunk by (o − 0.1 r)/(1 − 0.1) so that δ/r = 0.1, the
// mother's ratio; the Hertz force at birth follows from the new radius.
TEST(BirthOverlap, NoneAndMotherShrinkTheLoadedSpheres) {
  const FragmentTemplate& t = fragment_template();
  const double R = BirthPinch::R, ra = t.ra * R;
  const double o = (std::sqrt(1 - 2 * t.ra) + t.ra - 0.9) * R;
  for (BirthOverlap birth : {BirthOverlap::kNone, BirthOverlap::kMotherRatio}) {
    BirthPinch c(birth);
    Engine eng(std::move(c.p), c.o);
    BreakageModel model(eng, c.b);
    eng.step();
    ASSERT_EQ(model.check(), 1);
    const double cut = birth == BirthOverlap::kNone ? o : (o - 0.1 * ra) / 0.9;
    const double r_new = ra - cut;
    const Particles& p = eng.particles();
    ASSERT_EQ(p.size(), 34);
    int shrunk = 0;
    double volume = 0;
    for (int64_t s = 0; s < p.size(); ++s) {
      volume += 4.0 / 3.0 * std::numbers::pi * p.r[s] * p.r[s] * p.r[s];
      if (std::abs(p.r[s] - r_new) < 1e-12 * R) {
        ++shrunk;
        const double ratio = birth == BirthOverlap::kNone ? 0.0 : 0.1;
        EXPECT_NEAR(birth_platen_overlap(eng, s) / p.r[s], ratio, 1e-9);
        EXPECT_NEAR(p.m[s], kBirthRho * 4.0 / 3.0 * std::numbers::pi * r_new * r_new * r_new, 1e-9 * p.m[s]);  // density kept
      } else {
        EXPECT_LE(birth_platen_overlap(eng, s), 0.0);
      }
    }
    EXPECT_EQ(shrunk, 4);
    const double mother = 4.0 / 3.0 * std::numbers::pi * R * R * R;
    const double shaved = 4 * 4.0 / 3.0 * std::numbers::pi * (ra * ra * ra - r_new * r_new * r_new);
    EXPECT_NEAR(model.record().volume_lost_m3, mother * (1 - t.retained_fraction()) + shaved, 1e-12 * mother);
    EXPECT_NEAR(model.record().volume_lost_m3, mother - volume, 1e-12 * mother);  // an independent count
    const SplitEvent& ev = model.events().at(0);
    EXPECT_NEAR(ev.volume_retained_m3, volume, 1e-12 * mother);
    EXPECT_NEAR(ev.fragment_overlap_ratio, o / ra, 1e-9);  // as placed, before the shrink
    if (birth == BirthOverlap::kNone) {
      EXPECT_EQ(ev.fragment_contacts, 0);
      EXPECT_EQ(ev.fragment_force_N, 0.0);
    } else {
      const double e_star = 5.5e9 / (2 * (1 - 0.25 * 0.25));
      EXPECT_EQ(ev.fragment_contacts, 4);
      EXPECT_NEAR(ev.fragment_force_N, 4.0 / 3.0 * e_star * std::sqrt(r_new) * std::pow(0.1 * r_new, 1.5),
                  1e-8 * ev.fragment_force_N);
    }
    // The shrunk spheres' bonds are sized from the radii they were born with.
    for (int64_t k = 0; k < model.bond_count(); ++k) {
      const double r1 = p.r[model.bond_a(k)], r2 = p.r[model.bond_b(k)];
      EXPECT_NEAR(bond_section(c.b.bond, r1, r2).radius, 1.25 * 0.5 * (r1 + r2), 1e-15);
    }
  }
}

// The log of broken bonds: a fixed 0.1 mm sphere A and a very heavy one B
// (mass × 1e12: the bond cannot slow it) moving away at v = 0.011 m/s,
// dt = 1 ns. The bond is made at step 7 (tension-free, whatever the gap);
// after k updates it is stretched by U = k v dt and σ = k̄n U with
// k̄n = E/(2r) = 2.75e13 Pa/m; it breaks at the first k with
// σ > 3.3 MPa: k > 3.3e6 / (2.75e13 · 0.011 · 1e-9) = 10909.09, k = 10910,
// in tension, at step 7 + 10910.
TEST(BirthOverlap, BondBreakLogGivesTheAgeOfTheBond) {
  const double r = 1e-4, v = 0.011, dt = 1e-9;
  Particles p;
  p.append_sphere(0, 0, 0, r, kBirthRho, 0, 0, kFlagFixed);
  p.append_sphere(0, 0, 2 * r, r, kBirthRho, 1, 0, kFlagNone);
  p.m[1] *= 1e12;
  p.inertia[1] *= 1e12;
  p.vz[1] = v;
  EngineOptions o;
  o.gravity_z = 0;
  o.walls.bottom = o.walls.top = o.walls.cylinder = false;
  o.time_step = dt;
  o.skin = 1e-4;
  Engine eng(std::move(p), o);
  BreakageOptions b;
  b.strength.d0_m = 1e-3;
  BreakageModel model(eng, b);
  for (int k = 0; k < 7; ++k) eng.step();
  model.add_bond(0, 1);
  for (int k = 0; k < 12000 && model.bond_count() == 1; ++k) eng.step();
  ASSERT_EQ(model.bond_break_log().size(), 1u);
  const BondBreak& br = model.bond_break_log()[0];
  EXPECT_EQ(br.born_step, 7);
  EXPECT_EQ(br.age_steps, 10910);
  EXPECT_EQ(br.step, 7 + 10910);
  EXPECT_EQ(eng.step_count(), br.step);  // the step it broke in is the last one made
  EXPECT_NEAR(br.age_s, 10910 * dt, 1e-9 * br.age_s);
  EXPECT_NEAR(br.time_s, eng.time(), 1e-15);
  EXPECT_TRUE(br.tensile);
  EXPECT_EQ(br.generation, 0);
  EXPECT_EQ(br.radius_a_m, r);
  EXPECT_EQ(model.record().bonds_broken, 1);
}

}  // namespace
}  // namespace tg::dem::breakage

#include "dem/breakage/parallel_bond.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/errors.hpp"

using namespace tg::dem;
using namespace tg::dem::breakage;

// Two spheres of radius 0.1 mm touching along z; Table 1 parameters:
//   R̄ = 1.25 (0.1 + 0.1)/2 mm = 0.125 mm, A = π R̄² = 4.908738521e-8 m²,
//   k̄n = 5.5e9 / 2e-4 = 2.75e13 Pa/m,  k̄s = 2.2e9 / 2e-4 = 1.1e13 Pa/m.
namespace {
constexpr double kR = 1e-4, kDt = 1e-8;
const ParallelBondParams kP{};
const BondSection kS = bond_section(kP, kR, kR);
const Vec3 kXa{0, 0, 0}, kXb{0, 0, 2 * kR}, kN{0, 0, 1};

BondState drive(Vec3 v_rel, Vec3 w_rel, int steps) {
  BondState b;
  for (int i = 0; i < steps; ++i) update_bond(kS, {kN, v_rel, w_rel}, kDt, b);
  return b;
}
}  // namespace

TEST(ParallelBond, SectionOfTheStudy) {
  EXPECT_DOUBLE_EQ(kS.radius, 1.25e-4);
  EXPECT_NEAR(kS.area, 4.908738521234052e-08, 1e-20);
  EXPECT_NEAR(kS.inertia, std::numbers::pi * std::pow(1.25e-4, 4) / 4, 1e-30);
  EXPECT_NEAR(kS.polar, 2 * kS.inertia, 1e-30);
  EXPECT_DOUBLE_EQ(kS.kn, 2.75e13);
  EXPECT_DOUBLE_EQ(kS.ks, 1.1e13);
  // Unequal spheres: λ times the MEAN radius (the study's definition).
  EXPECT_DOUBLE_EQ(bond_section(kP, 2e-4, 1e-4).radius, 1.25 * 1.5e-4);
  EXPECT_DOUBLE_EQ(bond_section(kP, 2e-4, 1e-4).kn, 5.5e9 / 3e-4);
}

TEST(ParallelBond, PureTension) {
  // B leaves A at 1 mm/s for 100 steps of 10 ns: ΔU = 1 nm of opening.
  const BondState b = drive({0, 0, 1e-3}, {}, 100);
  EXPECT_NEAR(b.fn, -2.75e13 * 4.908738521234052e-08 * 1e-9, 1e-15);  // = −1.34990e-3 N
  EXPECT_NEAR(norm(b.fs), 0, 1e-20);
  EXPECT_NEAR(norm(b.mb), 0, 1e-25);
  EXPECT_EQ(b.mt, 0);
  const BondStress st = bond_stress(kS, b);
  EXPECT_NEAR(st.sigma_max, 2.75e13 * 1e-9, 1e-6);  // σ = k̄n U = 27.5 kPa
  EXPECT_NEAR(st.tau_max, 0, 1e-9);
  const BondLoads l = bond_loads(b, kN, kXa, kXb, bond_point(kXa, kR, kXb, kR));
  EXPECT_NEAR(l.force_on_b.z, b.fn, 1e-18);  // pulled back towards A
  EXPECT_NEAR(norm(l.torque_on_a) + norm(l.torque_on_b), 0, 1e-25);
}

TEST(ParallelBond, PureShear) {
  const BondState b = drive({1e-3, 0, 0}, {}, 100);  // 1 nm slip of B along +x
  const double fs = -1.1e13 * 4.908738521234052e-08 * 1e-9;  // −5.39961e-4 N
  EXPECT_NEAR(b.fs.x, fs, 1e-12 * std::abs(fs));
  EXPECT_NEAR(b.fs.y, 0, 1e-20);
  EXPECT_EQ(b.fn, 0);
  const BondStress st = bond_stress(kS, b);
  EXPECT_NEAR(st.tau_max, 1.1e13 * 1e-9, 1e-6);  // τ = k̄s U = 11 kPa
  EXPECT_NEAR(st.sigma_max, 0, 1e-9);
  // The shear force acts at the bond point (0,0,R): the couple turns both
  // spheres the same way: on B (−R ẑ) × (fs x̂) = −R fs ŷ, on A (R ẑ) × (−fs x̂) = −R fs ŷ.
  const BondLoads l = bond_loads(b, kN, kXa, kXb, bond_point(kXa, kR, kXb, kR));
  EXPECT_NEAR(l.torque_on_b.y, -kR * fs, 1e-12 * kR * std::abs(fs));
  EXPECT_NEAR(l.torque_on_a.y, -kR * fs, 1e-12 * kR * std::abs(fs));
  EXPECT_NEAR(l.force_on_b.x, fs, 1e-12 * std::abs(fs));
}

TEST(ParallelBond, PureBending) {
  // Counter-rotation about x at ±0.5 rad/s: the bond points do not move
  // relative to each other, θ = 1 rad/s × 1 µs = 1e-6 rad of bending.
  BondState b;
  const Vec3 xc = bond_point(kXa, kR, kXb, kR);
  const Vec3 wa{-0.5, 0, 0}, wb{0.5, 0, 0};
  const Vec3 v_rel = cross(wb, xc - kXb) - cross(wa, xc - kXa);
  EXPECT_NEAR(norm(v_rel), 0, 1e-20);
  for (int i = 0; i < 100; ++i) update_bond(kS, {kN, v_rel, wb - wa}, kDt, b);
  EXPECT_NEAR(b.mb.x, -2.75e13 * kS.inertia * 1e-6, 1e-20);  // rel. 1e-12 (100 summed increments)
  const BondStress st = bond_stress(kS, b);
  EXPECT_NEAR(st.sigma_max, 2.75e13 * 1e-6 * 1.25e-4, 1e-6);  // σ = k̄n θ R̄ = 3437.5 Pa
  EXPECT_NEAR(st.tau_max, 0, 1e-9);
}

TEST(ParallelBond, PureTwisting) {
  const BondState b = drive({}, {0, 0, 1.0}, 100);  // θ = 1e-6 rad about n
  EXPECT_NEAR(b.mt, -1.1e13 * kS.polar * 1e-6, 1e-20);  // rel. 1e-12
  const BondStress st = bond_stress(kS, b);
  EXPECT_NEAR(st.tau_max, 1.1e13 * 1e-6 * 1.25e-4, 1e-6);  // τ = k̄s θ R̄ = 1375 Pa
  EXPECT_NEAR(st.sigma_max, 0, 1e-9);
  const BondLoads l = bond_loads(b, kN, kXa, kXb, bond_point(kXa, kR, kXb, kR));
  EXPECT_NEAR(l.torque_on_b.z, b.mt, 1e-25);
  EXPECT_NEAR(l.torque_on_a.z, -b.mt, 1e-25);
}

TEST(ParallelBond, CompressionAloneNeverBreaks) {
  BondState b;
  b.fn = 1.0;  // 1 N of compression: σ = −F̄n/A < 0
  EXPECT_FALSE(bond_breaks(kP, kS, b));
}

TEST(ParallelBond, BreaksJustAboveTheStrengths) {
  // Tension: σ = k̄n U reaches 3.3 MPa at U = 3.3e6 / 2.75e13 = 120 nm.
  const double u = 3.3e6 / 2.75e13;
  BondState b;
  update_bond(kS, {kN, {0, 0, 0.999 * u / kDt}, {}}, kDt, b);
  EXPECT_FALSE(bond_breaks(kP, kS, b));
  update_bond(kS, {kN, {0, 0, 0.002 * u / kDt}, {}}, kDt, b);
  EXPECT_TRUE(bond_breaks(kP, kS, b));
  // Shear: τ = k̄s U reaches 3.3 MPa at U = 300 nm.
  const double us = 3.3e6 / 1.1e13;
  BondState c;
  update_bond(kS, {kN, {0.999 * us / kDt, 0, 0}, {}}, kDt, c);
  EXPECT_FALSE(bond_breaks(kP, kS, c));
  update_bond(kS, {kN, {0.002 * us / kDt, 0, 0}, {}}, kDt, c);
  EXPECT_TRUE(bond_breaks(kP, kS, c));
  // Bending: σ = k̄n θ R̄ reaches 3.3 MPa at θ = 3.3e6 / (2.75e13 × 1.25e-4) = 0.96 mrad.
  const double th = 3.3e6 / (2.75e13 * 1.25e-4);
  BondState d;
  update_bond(kS, {kN, {}, {0.999 * th / kDt, 0, 0}}, kDt, d);
  EXPECT_FALSE(bond_breaks(kP, kS, d));
  update_bond(kS, {kN, {}, {0.002 * th / kDt, 0, 0}}, kDt, d);
  EXPECT_TRUE(bond_breaks(kP, kS, d));
  // Twisting: τ = k̄s θ R̄ reaches 3.3 MPa at θ = 2.4 mrad.
  const double tw = 3.3e6 / (1.1e13 * 1.25e-4);
  BondState e;
  update_bond(kS, {kN, {}, {0, 0, 0.999 * tw / kDt}}, kDt, e);
  EXPECT_FALSE(bond_breaks(kP, kS, e));
  update_bond(kS, {kN, {}, {0, 0, 0.002 * tw / kDt}}, kDt, e);
  EXPECT_TRUE(bond_breaks(kP, kS, e));
}

TEST(ParallelBond, ShearForceTurnsWithTheBond) {
  // A rigid rotation of the pair (no relative motion) by 90° about y in
  // 2000 small steps: the stored shear force keeps its length and follows
  // the frame, x̂ → −ẑ, as the normal goes ẑ → x̂.
  BondState b;
  b.fs = {1e-3, 0, 0};
  b.mb = {0, 2e-9, 0};
  const int n = 2000;
  for (int i = 1; i <= n; ++i) {
    const double a = 0.5 * std::numbers::pi * i / n;
    update_bond(kS, {{std::sin(a), 0, std::cos(a)}, {}, {}}, kDt, b);
  }
  EXPECT_NEAR(norm(b.fs), 1e-3, 1e-15);
  EXPECT_NEAR(b.fs.z, -1e-3, 1e-6);
  EXPECT_NEAR(b.mb.y, 2e-9, 1e-20);  // along the rotation axis: unchanged
}

TEST(ParallelBond, RejectsBadParameters) {
  ParallelBondParams p;
  p.radius_multiplier = 0;
  EXPECT_THROW(validate(p), tg::InputError);
  p = {};
  p.tensile_strength_Pa = std::nan("");
  EXPECT_THROW(validate(p), tg::InputError);
  EXPECT_NO_THROW(validate(ParallelBondParams{}));
}

// The contact law alone, against its closed forms.
#include "dem/contact/hertz_mindlin.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"

namespace tg::dem {
namespace {

TEST(HertzMindlin, EffectiveModuli) {
  const Material m;  // G 2.2 GPa, ν 0.25
  const HertzMindlin law = make_hertz_mindlin(m, m, 0.5, 1.0);
  EXPECT_NEAR(law.e_star, 5.5e9 / (2 * (1 - 0.0625)), 1.0);
  EXPECT_NEAR(law.g_star, 2.2e9 / (2 * (2 - 0.25)), 1.0);
  EXPECT_EQ(law.damp_beta, 0.0);
}

TEST(HertzMindlin, NormalForceIsHertz) {
  const Material m;
  const HertzMindlin law = make_hertz_mindlin(m, m, 0.5, 1.0);
  const double r = 0.34e-3, delta = 1e-6;
  ContactGeometry g{{0, 0, 1}, delta, r, 1e-6, {0, 0, 0}};
  Vec3 xi{};
  const ContactForce f = hertz_mindlin_force(law, g, 1e-8, xi);
  EXPECT_NEAR(f.fn / (4.0 / 3.0 * law.e_star * std::sqrt(r) * std::pow(delta, 1.5)), 1.0, 1e-12);
  EXPECT_NEAR(f.force_on_j.z, f.fn, 0);
}

// Sticking regime: a small tangential displacement at fixed overlap gives
// Ft = kt ξ with kt / kn = 4 G*/E* = 2(1-ν)/(2-ν) for identical materials.
TEST(HertzMindlin, MindlinStiffnessRatioWhileSticking) {
  const Material m;
  const HertzMindlin law = make_hertz_mindlin(m, m, 0.5, 1.0);
  const double r = 0.34e-3, delta = 2e-6, dt = 1e-8;
  Vec3 xi{};
  ContactGeometry g{{0, 0, 1}, delta, r, 1e-6, {1e-3, 0, 0}};  // 1 mm/s sliding speed in x
  ContactForce f{};
  for (int s = 0; s < 10; ++s) f = hertz_mindlin_force(law, g, dt, xi);
  const double ut = 10 * dt * 1e-3;
  EXPECT_NEAR(xi.x, ut, 1e-20);
  EXPECT_FALSE(f.sliding);
  const double kt = -f.force_on_j.x / ut;
  const double kn = 2 * law.e_star * std::sqrt(r * delta);
  EXPECT_NEAR(kt / kn, 2 * (1 - 0.25) / (2 - 0.25), 1e-9);
}

TEST(HertzMindlin, CoulombCapWhileSliding) {
  const Material m;
  const HertzMindlin law = make_hertz_mindlin(m, m, 0.3, 1.0);
  ContactGeometry g{{0, 0, 1}, 1e-6, 0.34e-3, 1e-6, {0.0, 1.0, 0}};
  Vec3 xi{};
  ContactForce f{};
  for (int s = 0; s < 100; ++s) f = hertz_mindlin_force(law, g, 1e-7, xi);
  EXPECT_TRUE(f.sliding);
  EXPECT_NEAR(std::hypot(f.force_on_j.x, f.force_on_j.y), 0.3 * f.fn, 1e-12 * f.fn);
  EXPECT_LT(f.force_on_j.y, 0);  // opposes the relative motion of j
  // ξ shrunk to the capped force: unloading starts elastic from the cap.
  EXPECT_NEAR(-law.tangential_stiffness(1e-6, 0.34e-3) * xi.y, f.force_on_j.y, 1e-12 * f.fn);
}

TEST(HertzMindlin, HistoryRotatesIntoTangentPlane) {
  const Material m;
  const HertzMindlin law = make_hertz_mindlin(m, m, 10.0, 1.0);
  Vec3 xi{1e-9, 0, 0};
  const double s = std::sqrt(0.5);
  ContactGeometry g{{s, 0, s}, 1e-6, 0.34e-3, 1e-6, {0, 0, 0}};  // normal tilted 45°
  hertz_mindlin_force(law, g, 1e-8, xi);
  EXPECT_NEAR(dot(xi, g.n), 0.0, 1e-24);
  EXPECT_NEAR(norm(xi), 1e-9, 1e-21);
}

TEST(HertzMindlin, RejectsBadParameters) {
  Material m;
  EXPECT_THROW(make_hertz_mindlin(m, m, -0.1, 1.0), InputError);
  EXPECT_THROW(make_hertz_mindlin(m, m, 0.5, 0.0), InputError);
  EXPECT_THROW(make_hertz_mindlin(m, m, 0.5, 1.5), InputError);
  m.poisson_ratio = 0.6;
  EXPECT_THROW(make_hertz_mindlin(m, m, 0.5, 1.0), InputError);
  m.poisson_ratio = 0.25;
  m.shear_modulus_Pa = 0;
  EXPECT_THROW(make_hertz_mindlin(m, m, 0.5, 1.0), InputError);
}

TEST(HertzMindlin, RestitutionToBeta) {
  const Material m;
  const HertzMindlin law = make_hertz_mindlin(m, m, 0.5, 0.5);
  const double le = std::log(0.5);
  EXPECT_NEAR(law.damp_beta, -le / std::sqrt(le * le + M_PI * M_PI), 1e-15);
}

}  // namespace
}  // namespace tg::dem

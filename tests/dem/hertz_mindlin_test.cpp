// The contact law alone, against its closed forms.
#include "dem/contact/hertz_mindlin.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

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

// A normal that turns by 1e-4 rad: the history is rescaled by the series of
// sqrt(|ξ|²/|p|²) (e ~ 1e-8), which must keep its length as the square root
// does (to a few ulps) and leave it in the tangent plane.
TEST(HertzMindlin, HistoryKeepsItsLengthWhenTheNormalTurnsSlightly) {
  const Material m;
  const HertzMindlin law = make_hertz_mindlin(m, m, 10.0, 1.0);
  const double a = 1e-4;
  const Vec3 n{std::sin(a), 0, std::cos(a)};
  Vec3 xi{3e-9, -4e-9, 0};
  const double len = norm(xi);
  ContactGeometry g{n, 1e-6, 0.34e-3, 1e-6, {0, 0, 0}};
  hertz_mindlin_force(law, g, 1e-8, xi);
  EXPECT_NEAR(dot(xi, n), 0.0, 1e-24);
  EXPECT_NEAR(norm(xi) / len, 1.0, 4e-16);
}

// The contact loop computes two contacts at once (Lanes2); each lane must
// give the bits of the scalar law, over sticking, sliding, damped, tilted
// and history-free contacts, whatever the other lane holds.
TEST(HertzMindlin, TwoLanesGiveTheScalarBits) {
  const Material m;
  const HertzMindlin law = make_hertz_mindlin(m, m, 0.5, 0.5);  // damped
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  auto unit = [&] {
    Vec3 v{u(rng), u(rng), u(rng)};
    return (1.0 / norm(v)) * v;
  };
  auto contact = [&](int kind) {
    ContactGeometry g{unit(), 1e-7 * (1.5 + u(rng)), 0.34e-3 * (1.2 + 0.2 * u(rng)), 1e-6 * (1.1 + 0.1 * u(rng)),
                      Vec3{1e-2 * u(rng), 1e-2 * u(rng), 1e-2 * u(rng)}};
    Vec3 xi{};
    if (kind == 1) xi = 1e-9 * unit();                // small history: sticking
    if (kind == 2) xi = 1e-6 * unit();                // large history: sliding
    if (kind == 3) { xi = 1e-9 * unit(); xi = xi - dot(xi, g.n) * g.n; }  // already tangent
    return std::pair{g, xi};
  };
  int sliding = 0;
  for (int t = 0; t < 400; ++t) {
    auto [ga, xa] = contact(t % 4);
    auto [gb, xb] = contact((t / 4) % 4);
    const auto L = [](double p, double q) { return Lanes2{p, q}; };
    const auto V = [&](Vec3 p, Vec3 q) { return Vec3T<Lanes2>{L(p.x, q.x), L(p.y, q.y), L(p.z, q.z)}; };
    ContactGeometryT<Lanes2> g2{V(ga.n, gb.n), L(ga.delta, gb.delta), L(ga.r_eff, gb.r_eff), L(ga.m_eff, gb.m_eff),
                                V(ga.v_rel, gb.v_rel)};
    Vec3T<Lanes2> x2 = V(xa, xb);
    const ContactForceT<Lanes2> f2 = hertz_mindlin_force(law, g2, 1e-7, x2);
    const ContactForce fa = hertz_mindlin_force(law, ga, 1e-7, xa), fb = hertz_mindlin_force(law, gb, 1e-7, xb);
    for (int l = 0; l < 2; ++l) {
      const ContactForce& f = l ? fb : fa;
      const Vec3& x = l ? xb : xa;
      ASSERT_EQ(f2.force_on_j.x[l], f.force_on_j.x) << t;
      ASSERT_EQ(f2.force_on_j.y[l], f.force_on_j.y) << t;
      ASSERT_EQ(f2.force_on_j.z[l], f.force_on_j.z) << t;
      ASSERT_EQ(f2.fn[l], f.fn) << t;
      ASSERT_EQ(x2.x[l], x.x) << t;
      ASSERT_EQ(x2.y[l], x.y) << t;
      ASSERT_EQ(x2.z[l], x.z) << t;
      ASSERT_EQ(f2.sliding[l] != 0, f.sliding) << t;
      sliding += f.sliding;
    }
  }
  EXPECT_GT(sliding, 100);  // both regimes were exercised
  EXPECT_LT(sliding, 700);
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

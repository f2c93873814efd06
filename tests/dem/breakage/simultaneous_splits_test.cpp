// Many grains splitting in one breakage check (issue 23: the check's
// bookkeeping is one pass over the pairs and one over the bonds for all
// splits, not one per split). The oracle is the per-sphere reading of the
// model: each sphere's contact loads gathered by its own scan of the pair
// list (the engine's kept pair forces and wall reactions), its plane from
// splitting_plane(), and the mothers' bonds dropped, every other bond kept.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "dem/breakage/breakage.hpp"

namespace tg::dem::breakage {
namespace simultaneous_splits_test {

// Loads on sphere s, scanned independently of the model: every touching
// pair that names s (force on j stored; on i the opposite), contact point
// at r_i - δ/2 from i along the centre line, then the walls' reactions.
std::vector<ContactLoad> loads_by_scan(const Engine& e, int64_t s) {
  const Particles& p = e.particles();
  std::vector<ContactLoad> c;
  for (int64_t k = 0; k < e.pair_count(); ++k) {
    if (!e.pair_touching(k)) continue;
    const int64_t i = e.pair_i(k), j = e.pair_j(k);
    if (i != s && j != s) continue;
    const Vec3 xi{p.x[i], p.y[i], p.z[i]}, xj{p.x[j], p.y[j], p.z[j]};
    const Vec3 d = xj - xi;
    const double dist = norm(d);
    const Vec3 n = (1 / dist) * d;
    const Vec3 point = xi + (p.r[i] - 0.5 * (p.r[i] + p.r[j] - dist)) * n;
    const PairData& pd = e.pair_force(k);
    const Vec3 f{pd.fx, pd.fy, pd.fz};
    c.push_back({point, i == s ? -f : f});
  }
  const double* w = e.sphere_wall_forces(s);
  EXPECT_TRUE(w[0] == 0 && w[1] == 0 && w[2] == 0);  // no walls in this scene
  return c;
}

// A chain of 40 touching 1 mm grains along x (each pressed 10 µm into the
// next), no walls, no gravity, σt0 = 1 kPa: every breakable grain is over its
// strength at the first check. Every fifth grain (s % 5 == 2) is not
// breakable. Bonds: 0-1 (two mothers), 6-7 (a mother and a survivor),
// 12-17 (two survivors).
TEST(BreakageModel, ManySplitsInOneCheckMatchTheOneSphereReading) {
  constexpr int kGrains = 40;
  constexpr double r = 0.5e-3, gap = 2 * r - 10e-6;
  Particles p;
  for (int s = 0; s < kGrains; ++s)
    p.append_sphere(s * gap, 0, 0, r, 2180, s, 0, s % 5 == 2 ? kFlagNone : kFlagBreakable);
  EngineOptions o;
  o.gravity_z = 0;
  o.walls.bottom = o.walls.top = o.walls.cylinder = false;
  o.time_step = 1e-8;
  Engine e(std::move(p), o);
  BreakageOptions b;
  b.strength.sigma_t0_Pa = 1e3;
  b.strength.d0_m = 1e-3;
  b.sublimit = SublimitPolicy::kKeep;  // no fines: indices stay put
  BreakageModel m(e, b);
  m.add_bond(0, 1);
  m.add_bond(6, 7);
  m.add_bond(12, 17);
  e.step();  // forces (and the kept pair forces) of this configuration

  // The oracle, from the state the check sees.
  const Particles& q = e.particles();
  std::vector<int64_t> expect_sphere;
  std::vector<SplittingPlane> expect_plane;
  for (int64_t s = 0; s < kGrains; ++s) {
    if (!(q.flags[s] & kFlagBreakable)) continue;
    const double d = 2 * q.r[s];
    const auto plane = splitting_plane({q.x[s], q.y[s], q.z[s]}, std::numbers::pi / 6 * d * d * d, loads_by_scan(e, s));
    if (!plane) continue;
    expect_sphere.push_back(s);
    expect_plane.push_back(*plane);
  }
  ASSERT_GE(expect_sphere.size(), 30u);  // 32 breakable grains, all loaded

  const int splits = m.check();
  ASSERT_EQ(splits, static_cast<int>(expect_sphere.size()));
  ASSERT_EQ(m.events().size(), expect_sphere.size());
  for (size_t k = 0; k < expect_sphere.size(); ++k) {
    const SplitEvent& ev = m.events()[k];
    EXPECT_EQ(ev.sphere, expect_sphere[k]);
    EXPECT_EQ(ev.plane.normal.x, expect_plane[k].normal.x);  // the same bits
    EXPECT_EQ(ev.plane.normal.y, expect_plane[k].normal.y);
    EXPECT_EQ(ev.plane.normal.z, expect_plane[k].normal.z);
    EXPECT_EQ(ev.plane.f_max, expect_plane[k].f_max);
    EXPECT_EQ(ev.plane.rule, expect_plane[k].rule);
  }
  // Bonds 0-1 and 6-7 went with their mothers; 12-17 stays, first in the list.
  EXPECT_EQ(m.record().bonds_dropped, 2);
  ASSERT_GE(m.bond_count(), 1);
  EXPECT_EQ(m.bond_a(0), 12);
  EXPECT_EQ(m.bond_b(0), 17);
  // Every new bond joins two spheres of one mother: its own index (kept by a
  // fragment sphere) or the spheres its split appended, in split order.
  const int64_t per_split = (e.particles().size() - kGrains) / splits;
  ASSERT_EQ(kGrains + per_split * splits, e.particles().size());
  auto mother_of = [&](int64_t t) { return t < kGrains ? t : m.events()[(t - kGrains) / per_split].sphere; };
  ASSERT_EQ((m.bond_count() - 1) % splits, 0);
  for (int64_t k = 1; k < m.bond_count(); ++k) {
    EXPECT_EQ(mother_of(m.bond_a(k)), mother_of(m.bond_b(k))) << "bond " << k;
    EXPECT_EQ(mother_of(m.bond_a(k)), m.events()[(k - 1) / ((m.bond_count() - 1) / splits)].sphere) << "bond " << k;
  }
}

}  // namespace simultaneous_splits_test
}  // namespace tg::dem::breakage

// data_synth/motion: the oedometer stage series' bookkeeping on a handful of
// grains (fast; the kinematics against the strain are checked on a rendered
// series in series_test.cpp).
#include "data_synth/motion.hpp"

#include <gtest/gtest.h>

#include <map>
#include <set>

using namespace tg::synth;

namespace {
std::vector<Particle> grains() {
  std::vector<Particle> g;
  for (uint32_t q = 0; q < 40; ++q)
    g.push_back(make_grain(q + 1, {10.0 + 20 * (q / 8), 10.0 + 20 * ((q / 4) % 2), 10.0 + 20 * (q % 4)}, 9.0));
  return g;
}
}  // namespace

// Ids unique per stage; every particle's parent exists at the previous stage;
// each event comes with the right kind of piece; the broken share follows `broken`.
TEST(Motion, LineageIsConsistent) {
  StageOptions so;
  so.broken = {0.0, 0.3, 0.5, 0.8, 1.0};
  MotionOptions mo;
  mo.oedometer = true;
  mo.rebreak = 0.5;
  const auto g = grains();
  std::set<uint32_t> prev;
  int64_t rebroken = 0;
  for (int s = 0; s < 5; ++s) {
    const auto ps = oedometer_stage(g, 0.0, s, so, mo);
    std::set<uint32_t> ids, grains_broken;
    for (const auto& p : ps) {
      EXPECT_TRUE(ids.insert(p.particle.id).second) << "stage " << s;
      if (s == 0) {
        EXPECT_EQ(p.parent, 0u);
        continue;
      }
      EXPECT_TRUE(prev.count(p.parent)) << "stage " << s << " id " << p.particle.id;
      if (p.event == "chip") {
        EXPECT_EQ(p.particle.kind, Kind::chip);
      }
      if (p.event == "chipping") {
        EXPECT_EQ(p.particle.kind, Kind::chipped);
      }
      if (p.event == "split" && p.parent != p.grain) ++rebroken;
      if (p.particle.id != p.grain) grains_broken.insert(p.grain);
    }
    if (s == 4) {
      EXPECT_EQ(grains_broken.size(), g.size());  // broken[4] = 1
    }
    if (s == 0) {
      EXPECT_EQ(ps.size(), g.size());
    }
    prev = ids;
  }
  EXPECT_GT(rebroken, 0);
}

// Same seed, same series; the grains near the top move down by the strain x height.
TEST(Motion, DeterministicAndCompressed) {
  StageOptions so;
  MotionOptions mo;
  mo.oedometer = true;
  mo.jitter = 0;
  mo.drift = 0;
  const auto g = grains();
  const auto a = oedometer_stage(g, 0.0, 2, so, mo), b = oedometer_stage(g, 0.0, 2, so, mo);
  ASSERT_EQ(a.size(), b.size());
  for (size_t q = 0; q < a.size(); ++q) {
    EXPECT_EQ(a[q].particle.id, b[q].particle.id);
    EXPECT_EQ(a[q].particle.pieces[0].sphere.c, b[q].particle.pieces[0].sphere.c);
  }
  const auto s0 = oedometer_stage(g, 0.0, 0, so, mo), s4 = oedometer_stage(g, 0.0, 4, so, mo);
  std::map<uint32_t, double> z0;
  for (const auto& p : s0) z0[p.particle.id] = p.particle.pieces[0].sphere.c[0];
  for (const auto& p : s4)
    if (p.event == "intact" && p.particle.id == p.grain) {  // intact: the sphere centre is the grain's
      EXPECT_NEAR(p.particle.pieces[0].sphere.c[0], z0[p.grain] * (1 - so.strains[4]) / (1 - so.strains[0]), 1e-9);
    }
}

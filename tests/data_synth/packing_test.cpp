#include "data_synth/packing.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

using namespace tg::synth;

TEST(Packing, ZeoliteCylinderIsDenseWithoutOverlaps) {
  // The reference specimen at reduced height (Ø15 mm, D50 1.36 mm, Cu 1.07).
  PackingOptions o;
  o.height = 6.0;
  const Packing p = dense_packing(o);
  std::printf("N=%zu fraction=%.4f interior=%.4f sweeps=%d removed=%d scale=%.9f contacts=%.2f\n",
              p.spheres.size(), p.fraction, p.interior_fraction, p.sweeps, p.removed, p.final_scale,
              p.mean_contacts);
  EXPECT_LE(max_overlap(p.spheres), 0.0);  // brute-force O(N²) oracle
  EXPECT_GE(p.interior_fraction, 0.55);
  EXPECT_GT(p.final_scale, 0.9999);
  EXPECT_GT(p.mean_contacts, 4.0);  // touching: a jammed packing has ~6
  for (const Sphere& s : p.spheres) {
    EXPECT_LE(std::hypot(s.c[1], s.c[2]) + s.r, 7.5 + 1e-12);
    EXPECT_GE(s.c[0] - s.r, -1e-12);
    EXPECT_LE(s.c[0] + s.r, 6.0 + 1e-12);
  }
}

TEST(Packing, BoxSizesFollowTheDistribution) {
  PackingOptions o;
  o.container = Container::box;
  o.height = o.box_y = o.box_x = 8;
  o.d50 = 1.0;
  o.cu = 1.3;
  o.seed = 5;
  const Packing p = dense_packing(o);
  EXPECT_LE(max_overlap(p.spheres), 0.0);
  EXPECT_GE(p.interior_fraction, 0.55);
  std::vector<double> d;
  for (const Sphere& s : p.spheres) d.push_back(2 * s.r);
  std::sort(d.begin(), d.end());
  const double d10 = d[d.size() / 10], d50 = d[d.size() / 2], d60 = d[d.size() * 6 / 10];
  EXPECT_NEAR(d50, 1.0, 0.03);
  EXPECT_NEAR(d60 / d10, 1.3, 0.08);  // sampling error of a few hundred grains
}

TEST(Packing, SameSeedSamePacking) {
  PackingOptions o;
  o.container = Container::box;
  o.height = o.box_y = o.box_x = 5;
  o.d50 = 1.0;
  const Packing a = dense_packing(o), b = dense_packing(o);
  ASSERT_EQ(a.spheres.size(), b.spheres.size());
  for (size_t q = 0; q < a.spheres.size(); ++q) EXPECT_EQ(a.spheres[q].c, b.spheres[q].c);
}

TEST(Packing, RejectsImpossibleContainers) {
  PackingOptions o;
  o.diameter = 1.0;
  EXPECT_THROW(dense_packing(o), tg::InputError);
  o = {};
  o.target_fraction = 0.9;
  EXPECT_THROW(dense_packing(o), tg::InputError);
}

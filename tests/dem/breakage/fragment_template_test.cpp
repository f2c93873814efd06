#include "dem/breakage/fragment_template.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <vector>

using namespace tg::dem;
using namespace tg::dem::breakage;

namespace {
double gap(const TemplateSphere& a, const TemplateSphere& b) { return norm(a.c - b.c) - a.r - b.r; }
}  // namespace

TEST(FragmentTemplate, SeventeenSpheresOfThreeSizes) {
  const auto& t = fragment_template();
  EXPECT_NEAR(t.rc, 0.449483162983, 1e-9);  // closed forms in the header, evaluated by hand
  EXPECT_NEAR(t.ra, 0.263301140817, 1e-9);
  EXPECT_NEAR(t.rb, 0.160974961873, 1e-9);
  EXPECT_DOUBLE_EQ(t.spheres[0].r, t.rc);
  for (int k = 1; k <= 8; ++k) EXPECT_DOUBLE_EQ(t.spheres[k].r, t.ra);
  for (int k = 9; k <= 16; ++k) EXPECT_DOUBLE_EQ(t.spheres[k].r, t.rb);
}

TEST(FragmentTemplate, SixteenTangentToMotherNoneCrossesPlane) {
  const auto& t = fragment_template();
  for (int k = 0; k < 17; ++k) {
    const auto& s = t.spheres[k];
    EXPECT_GE(s.c.z - s.r, -1e-14) << k;       // on the z > 0 side of the plane
    EXPECT_LE(norm(s.c) + s.r, 1 + 1e-14) << k;  // inside the mother
    if (k > 0) {
      EXPECT_NEAR(norm(s.c) + s.r, 1.0, 1e-12) << k;  // internally tangent
    }
  }
  // Ring A and the central sphere lie on the plane (flat fracture face).
  for (int k = 0; k <= 8; ++k) EXPECT_NEAR(t.spheres[k].c.z, t.spheres[k].r, 1e-14);
  // Ring B centres at polar angle 45°.
  const auto& b = t.spheres[9].c;
  EXPECT_NEAR(std::atan2(std::hypot(b.x, b.y), b.z), std::numbers::pi / 4, 1e-9);
}

TEST(FragmentTemplate, BondsAreExactlyTheTangentPairsAndConnectTheCluster) {
  const auto& t = fragment_template();
  ASSERT_EQ(t.bonds.size(), 40u);
  std::set<std::pair<int, int>> bonded;
  for (auto b : t.bonds) {
    ASSERT_LT(b[0], b[1]);
    EXPECT_TRUE(bonded.insert({b[0], b[1]}).second) << "duplicate bond";
    EXPECT_NEAR(gap(t.spheres[b[0]], t.spheres[b[1]]), 0.0, 1e-12) << b[0] << "-" << b[1];
  }
  double min_unbonded = 1e9;
  for (int i = 0; i < 17; ++i)
    for (int j = i + 1; j < 17; ++j)
      if (!bonded.count({i, j})) min_unbonded = std::min(min_unbonded, gap(t.spheres[i], t.spheres[j]));
  EXPECT_NEAR(min_unbonded, 0.1321, 1e-3);  // no unbonded pair touches (no locked-in contact force)
  // Connected: flood from sphere 0 over bonds.
  std::vector<int> seen(17, 0);
  seen[0] = 1;
  for (int pass = 0; pass < 17; ++pass)
    for (auto b : t.bonds)
      if (seen[b[0]] || seen[b[1]]) seen[b[0]] = seen[b[1]] = 1;
  for (int k = 0; k < 17; ++k) EXPECT_TRUE(seen[k]) << k;
}

// Independent check of the retained volume: count the cells of a fine grid
// whose centre lies in the union of the 17 spheres (overlaps counted once by
// construction of a boolean mask). Midpoint counting of smooth bodies errs by
// far less than h = 1/128 of the radius; measured 0.5405 vs 0.5404.
TEST(FragmentTemplate, RetainedFractionMatchesGridUnion) {
  const auto& t = fragment_template();
  EXPECT_NEAR(t.retained_fraction(), 0.5404, 1e-4);
  const int n = 128;  // cells per mother radius
  const double h = 1.0 / n;
  std::vector<uint8_t> in(static_cast<size_t>(2 * n) * 2 * n * n, 0);  // x, y in [-1,1], z in [0,1]
  for (const auto& s : t.spheres) {
    const int i0 = std::max(0, int(std::floor((s.c.x - s.r + 1) / h))), i1 = std::min(2 * n - 1, int((s.c.x + s.r + 1) / h));
    const int j0 = std::max(0, int(std::floor((s.c.y - s.r + 1) / h))), j1 = std::min(2 * n - 1, int((s.c.y + s.r + 1) / h));
    const int k0 = std::max(0, int(std::floor((s.c.z - s.r) / h))), k1 = std::min(n - 1, int((s.c.z + s.r) / h));
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const double x = -1 + (i + 0.5) * h - s.c.x, y = -1 + (j + 0.5) * h - s.c.y, z = (k + 0.5) * h - s.c.z;
          if (x * x + y * y + z * z <= s.r * s.r) in[(static_cast<size_t>(k) * 2 * n + j) * 2 * n + i] = 1;
        }
  }
  double count = 0;
  for (auto v : in) count += v;
  const double fraction = 2 * count * h * h * h / (4.0 / 3.0 * std::numbers::pi);
  EXPECT_NEAR(fraction, t.retained_fraction(), 2e-3);
  EXPECT_NEAR(fraction, 0.54, 5e-3);  // the study: 46 % lost
}

TEST(FragmentTemplate, ShapeExtentsFlatnessAndAspect) {
  const auto& t = fragment_template();
  double zmax = 0, xmax = 0;
  for (const auto& s : t.spheres) {
    zmax = std::max(zmax, s.c.z + s.r);
    xmax = std::max(xmax, std::hypot(s.c.x, s.c.y) + s.r);  // largest radial reach (ring A)
  }
  EXPECT_NEAR(zmax, 2 * t.rc, 1e-12);  // the central sphere is the top
  // Dmin = height, Dmed = Dmax = diameter along an A axis: FR ≈ 0.47, AR ≈ 2.12
  // (the half-sphere: 0.5 and 2).
  EXPECT_NEAR(zmax / (2 * xmax), 0.4725, 1e-3);
  EXPECT_NEAR(2 * xmax / zmax, 2.116, 1e-3);
  const Vec3 c = t.centroid();
  EXPECT_NEAR(c.x, 0, 1e-12);
  EXPECT_NEAR(c.y, 0, 1e-12);
  EXPECT_NEAR(c.z, 0.3666, 1e-3);  // the half-sphere: 3/8
}

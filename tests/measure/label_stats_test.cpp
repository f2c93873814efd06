#include "measure/label_stats.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "tests/measure/shapes.hpp"

namespace tg::measure {
namespace {

using test::V3;

// A volume with overlapping shapes, a touching-the-border blob, scattered
// single voxels and sparse label values (incl. > 2^24 to exercise the
// non-table label index when `big` is set).
Volume<uint32_t> mixed_volume(bool big) {
  const uint32_t off = big ? (1u << 30) : 0u;
  auto v = test::draw(Shape{30, 34, 38},
                      {{off + 7, test::sphere(V3(12, 14, 15), 8.3)},
                       {off + 3, test::ellipsoid(V3(18, 20, 24), V3(9, 5, 3), test::random_rotation(3))},
                       {off + 900, test::box(V3(2, 30, 35), V3(6, 9, 7), test::random_rotation(4))}});
  std::mt19937 rng(5);
  for (int n = 0; n < 60; ++n) v[std::uniform_int_distribution<int64_t>(0, v.size() - 1)(rng)] = off + 40 + n % 7;
  Geometry g = v.geometry();
  g.voxel_size_m = {2e-5, 1e-5, 1.5e-5};  // anisotropic
  g.origin_m = {1e-3, -2e-3, 0.5e-3};
  v.set_geometry(g);
  return v;
}

// The naive oracle: every label scanned over the whole volume, in doubles.
struct Naive {
  int64_t n = 0;
  V3 sum = V3::Zero();
  Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
  std::array<int64_t, 3> lo{1 << 30, 1 << 30, 1 << 30}, hi{-1, -1, -1};
  bool border = false;
  std::vector<std::array<int64_t, 4>> surface;  // k, j, i, mask
};

std::map<uint32_t, Naive> naive(const Volume<uint32_t>& v) {
  std::map<uint32_t, Naive> out;
  const Shape s = v.shape();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        const uint32_t l = v(k, j, i);
        if (!l) continue;
        Naive& a = out[l];
        const V3 p(k, j, i);
        ++a.n;
        a.sum += p;
        a.sq += p * p.transpose();
        a.lo = {std::min(a.lo[0], k), std::min(a.lo[1], j), std::min(a.lo[2], i)};
        a.hi = {std::max(a.hi[0], k + 1), std::max(a.hi[1], j + 1), std::max(a.hi[2], i + 1)};
        const int64_t d[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
        int64_t mask = 0;
        for (int f = 0; f < 6; ++f) {
          const int64_t kk = k + d[f][0], jj = j + d[f][1], ii = i + d[f][2];
          if (!s.contains(kk, jj, ii)) {
            a.border = true;
            mask |= 1 << f;
          } else if (v(kk, jj, ii) != l) {
            mask |= 1 << f;
          }
        }
        if (mask) a.surface.push_back({k, j, i, mask});
      }
  return out;
}

void expect_matches_naive(const Volume<uint32_t>& v) {
  const auto r = label_stats(v.view());
  const auto ref = naive(v);
  ASSERT_EQ(r.labels.size(), ref.size());
  const auto& h = v.geometry().voxel_size_m;
  size_t n = 0;
  for (const auto& [label, a] : ref) {
    const LabelStats& st = r.labels[n];
    EXPECT_EQ(st.label, label);
    EXPECT_EQ(st.voxels, a.n);
    EXPECT_NEAR(st.volume_m3, a.n * h[0] * h[1] * h[2], 1e-12 * st.volume_m3);
    const V3 mean = a.sum / a.n;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(st.centroid_m[c], v.geometry().origin_m[c] + (mean[c] + 0.5) * h[c], 1e-12);
    EXPECT_EQ(st.box_lo, a.lo);
    EXPECT_EQ(st.box_hi, a.hi);
    EXPECT_EQ(st.touches_border, a.border);
    // Second moment in metres, with each voxel's own h^2/12.
    Eigen::Matrix3d C = a.sq / a.n - mean * mean.transpose();
    const V3 hv(h[0], h[1], h[2]);
    C = hv.asDiagonal() * C * hv.asDiagonal();
    for (int c = 0; c < 3; ++c) C(c, c) += h[c] * h[c] / 12;
    C *= st.volume_m3;
    const Eigen::Matrix3d I = C.trace() * Eigen::Matrix3d::Identity() - C;
    EXPECT_LT((st.inertia_m5 - I).norm(), 1e-9 * I.norm() + 1e-40);
    // Principal axes diagonalise the tensor.
    const Eigen::Matrix3d D = st.principal_axes.transpose() * st.inertia_m5 * st.principal_axes;
    EXPECT_LT((D - Eigen::Matrix3d(st.principal_moments_m5.asDiagonal())).norm(), 1e-9 * I.norm() + 1e-40);
    const auto surf = r.surface_of(n);
    ASSERT_EQ(surf.size(), a.surface.size()) << "label " << label;
    for (size_t q = 0; q < surf.size(); ++q) {
      EXPECT_EQ(surf[q].k, a.surface[q][0]);
      EXPECT_EQ(surf[q].j, a.surface[q][1]);
      EXPECT_EQ(surf[q].i, a.surface[q][2]);
      EXPECT_EQ(surf[q].exposed, a.surface[q][3]);
    }
    ++n;
  }
}

TEST(LabelStats, MatchesNaiveOracle) { expect_matches_naive(mixed_volume(false)); }
TEST(LabelStats, MatchesNaiveOracleLargeLabelValues) { expect_matches_naive(mixed_volume(true)); }

TEST(LabelStats, ThreadCountDoesNotChangeResult) {
  const auto v = mixed_volume(false);
  LabelStatsOptions o1, o2, o3;
  o1.threads = 1;
  o2.threads = 2;
  o3.threads = 7;  // more threads than this machine has cores, uneven slabs
  const auto a = label_stats(v.view(), o1), b = label_stats(v.view(), o2), c = label_stats(v.view(), o3);
  for (const auto* x : {&b, &c}) {
    ASSERT_EQ(a.labels.size(), x->labels.size());
    for (size_t n = 0; n < a.labels.size(); ++n) {
      EXPECT_EQ(a.labels[n].centroid_m, x->labels[n].centroid_m);  // bit-identical
      EXPECT_EQ(a.labels[n].inertia_m5, x->labels[n].inertia_m5);
    }
    ASSERT_EQ(a.surface.size(), x->surface.size());
    for (size_t q = 0; q < a.surface.size(); ++q) {
      EXPECT_EQ(a.surface[q].k, x->surface[q].k);
      EXPECT_EQ(a.surface[q].i, x->surface[q].i);
      EXPECT_EQ(a.surface[q].exposed, x->surface[q].exposed);
    }
  }
}

TEST(LabelStats, SphereVolumeCentroidAndEquivalentDiameter) {
  const double r = 15;
  const V3 c(20.3, 19.8, 20.1);
  const auto v = test::draw(Shape{42, 42, 42}, {{1, test::sphere(c, r)}}, 1e-5);
  const auto st = label_stats(v.view()).labels.at(0);
  // Digitised sphere volume within 0.5 % of 4/3 pi r^3 at r = 15.
  EXPECT_NEAR(st.volume_m3 / (4.0 / 3 * std::numbers::pi * r * r * r * 1e-15), 1.0, 0.005);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(st.centroid_m[a], c[a] * 1e-5, 0.02e-5);
  EXPECT_NEAR(st.d_eq_m / (2 * r * 1e-5), 1.0, 0.002);
  EXPECT_FALSE(st.touches_border);
  // Inertia of a solid sphere: (2/5) M r^2 about every axis (unit density).
  const double I = 0.4 * st.volume_m3 * std::pow(r * 1e-5, 2);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(st.principal_moments_m5[a] / I, 1.0, 0.01);
}

TEST(LabelStats, RotatedBoxPrincipalAxes) {
  const Eigen::Matrix3d R = test::random_rotation(11);
  const V3 e(30, 16, 8);
  const auto v = test::draw(Shape{40, 40, 40}, {{5, test::box(V3(20, 20, 20), e, R)}}, 1e-5);
  const auto st = label_stats(v.view()).labels.at(0);
  // Box inertia: I_a = M/12 (e_b^2 + e_c^2); smallest about the longest edge.
  const double M = e.prod();
  const V3 ref(M / 12 * (16 * 16 + 8 * 8), M / 12 * (30 * 30 + 8 * 8), M / 12 * (30 * 30 + 16 * 16));
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(st.principal_moments_m5[a] * 1e25 / ref[a], 1.0, 0.03);
  // The axis of the smallest moment is the longest edge (|cos| > 0.999).
  EXPECT_GT(std::abs(st.principal_axes.col(0).dot(R.col(0))), 0.999);
}

TEST(LabelStats, FlagsBorderAndDetectionLimit) {
  auto v = test::draw(Shape{20, 20, 20}, {{1, test::sphere(V3(10, 10, 10), 6)}, {2, test::sphere(V3(0, 10, 10), 3)}},
                      2e-5);  // 20 um voxels: sphere 1 has d ~ 0.24 mm, sphere 2 (a cut half) ~0.09 mm
  LabelStatsOptions o;
  auto r = label_stats(v.view(), o);
  ASSERT_EQ(r.labels.size(), 2u);
  EXPECT_FALSE(r.labels[0].touches_border);
  EXPECT_TRUE(r.labels[1].touches_border);
  EXPECT_FALSE(r.labels[0].below_limit);
  EXPECT_TRUE(r.labels[1].below_limit);
  o.detection_limit_m = 0.3e-3;
  r = label_stats(v.view(), o);
  EXPECT_TRUE(r.labels[0].below_limit);
}

TEST(LabelStats, EmptyVolumeAndMissingVoxelSize) {
  auto v = Volume<uint32_t>::filled(Shape{4, 5, 6}, 0, Geometry::isotropic_m(1e-5));
  EXPECT_TRUE(label_stats(v.view()).labels.empty());
  v.set_geometry(Geometry{});
  EXPECT_THROW(label_stats(v.view()), UsageError);
}

TEST(LabelStats, SingleVoxelIsAllSurface) {
  auto v = Volume<uint32_t>::filled(Shape{3, 3, 3}, 0, Geometry::isotropic_m(1e-5));
  v(1, 1, 1) = 9;
  const auto r = label_stats(v.view());
  ASSERT_EQ(r.surface.size(), 1u);
  EXPECT_EQ(r.surface[0].exposed, 63);
}

// Equivalent ellipsoid of rotated ellipsoids (semi-axes 24, 14, 9 voxels,
// random rotation and sub-voxel centre, seeds 1-4): semi-axes within 1 %
// (skimage's test_3d_ellipsoid_axis_lengths bar), major axis within 1 deg.
TEST(LabelStats, EquivalentEllipsoidOfRotatedEllipsoids) {
  const V3 semi(24, 14, 9);
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const Eigen::Matrix3d R = test::random_rotation(seed);
    const auto v = test::draw_one(24, [&](V3 c) { return test::ellipsoid(c, semi, R); }, seed);
    const auto r = label_stats(v.view());
    ASSERT_EQ(r.labels.size(), 1u);
    const auto& st = r.labels[0];
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(st.ellipsoid_semi_axes_m[a] / 1e-5, semi[a], 0.01 * semi[a]) << seed;
    const double c = std::abs(st.ellipsoid_axes.col(0).dot(R.col(0)));
    EXPECT_GE(c, std::cos(1.0 * std::numbers::pi / 180)) << seed;
  }
}

// One voxel: the moments of a cube, semi-axes sqrt(5/12) h each.
TEST(LabelStats, EquivalentEllipsoidOfOneVoxel) {
  auto v = Volume<uint32_t>::filled(Shape{3, 3, 3}, 0, Geometry::isotropic_m(1e-5));
  v(1, 1, 1) = 5;
  const auto r = label_stats(v.view());
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(r.labels[0].ellipsoid_semi_axes_m[a], std::sqrt(5.0 / 12) * 1e-5, 1e-15);
}

}  // namespace
}  // namespace tg::measure

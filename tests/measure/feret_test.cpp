#include "measure/feret.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "measure/label_stats.hpp"
#include "tests/measure/shapes.hpp"

namespace tg::measure {
namespace {

using test::V3;

// Hull of a one-label volume drawn in voxel units (voxel size 1).
struct Measured {
  ConvexHull hull;
  double volume = 0;
};
Measured hull_of(const Volume<uint32_t>& v, double face_offset = 0.3) {
  const auto r = label_stats(v.view());
  EXPECT_EQ(r.labels.size(), 1u);
  const auto pts = caliper_points(r.surface_of(0), v.geometry().voxel_size_m, r.labels[0].box_lo, face_offset);
  return {convex_hull(pts), r.labels[0].volume_m3};
}

std::vector<Vec3> cloud(unsigned seed, int n) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  const Eigen::Matrix3d R = test::random_rotation(seed);
  std::vector<Vec3> p;
  for (int k = 0; k < n; ++k) p.push_back(R * V3(5 * g(rng), 2 * g(rng), 1 * g(rng)));
  return p;
}

// Half a voxel: the Dmax tie tolerance the particle table uses.
const FeretExactOptions tie{0.5, 20.0};

double dmed(double volume, double dmax, double dmin) { return 6 * volume / (std::numbers::pi * dmax * dmin); }

TEST(FeretDirections, UnitUpperHalfAndQuasiUniform) {
  const int n = 60;
  const auto d = half_sphere_directions(n);
  ASSERT_EQ(d.size(), 60u);
  for (const auto& u : d) {
    EXPECT_NEAR(u.norm(), 1.0, 1e-12);
    EXPECT_GT(u.z(), 0.0);
  }
  // Covering radius: every direction of a dense probe set lies within
  // 1.2 * sqrt(2 pi / N) rad of some +-u (the mean spacing is sqrt(2 pi / N)).
  const double bound = 1.2 * std::sqrt(2 * std::numbers::pi / n);
  double worst = 0;
  for (const auto& q : half_sphere_directions(20000)) {
    double best = 0;
    for (const auto& u : d) best = std::max(best, std::abs(q.dot(u)));
    worst = std::max(worst, std::acos(std::min(1.0, best)));
  }
  EXPECT_LT(worst, bound);
}

TEST(FeretExact, UnitCube) {
  std::vector<Vec3> c;
  for (int a = 0; a < 8; ++a) c.emplace_back(a & 1, (a >> 1) & 1, (a >> 2) & 1);
  const auto h = convex_hull(c);
  EXPECT_NEAR(hull_diameter(h), std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(min_width(h), 1.0, 1e-12);
  EXPECT_NEAR(caliper_width(h, V3(1, 1, 1).normalized()), std::sqrt(3.0), 1e-12);
  // Projection along the space diagonal is a regular hexagon of side sqrt(2/3): width sqrt(2).
  EXPECT_NEAR(min_width_perpendicular(h, V3(1, 1, 1)), std::sqrt(2.0), 1e-12);
}

TEST(FeretExact, RegularTetrahedronEdgeEdgeWidth) {
  // The minimum width of a regular tetrahedron is between opposite edges
  // (edge / sqrt 2 = 2 here), below its face-vertex height (2.309): only the
  // edge-edge search finds it.
  const std::vector<Vec3> t{V3(1, 1, 1), V3(1, -1, -1), V3(-1, 1, -1), V3(-1, -1, 1)};
  const Eigen::Matrix3d R = test::random_rotation(8);
  std::vector<Vec3> r;
  for (const auto& p : t) r.push_back(R * p);
  const auto h = convex_hull(r);
  Vec3 dir;
  EXPECT_NEAR(min_width(h, &dir), 2.0, 1e-12);
  EXPECT_NEAR(caliper_width(h, dir), 2.0, 1e-12);
}

TEST(FeretExact, DiameterEqualsBruteForceMaxDistance) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto p = cloud(seed, 400);
    double brute = 0;
    for (size_t a = 0; a < p.size(); ++a)
      for (size_t b = a + 1; b < p.size(); ++b) brute = std::max(brute, (p[a] - p[b]).norm());
    EXPECT_NEAR(hull_diameter(convex_hull(p)), brute, 1e-12 * brute);
  }
}

TEST(FeretExact, MinWidthMatchesDenseDirectionScan) {
  const auto dirs = half_sphere_directions(200000);  // ~0.0056 rad apart
  for (unsigned seed : {4u, 5u, 6u}) {
    const auto h = convex_hull(cloud(seed, 300));
    const double exact = min_width(h);
    double dense = 1e300;
    for (const auto& u : dirs) dense = std::min(dense, caliper_width(h, u));
    // The exact minimum can only be below any sampled width, and a dense scan
    // comes within its angular step (width error ~ diameter * step^2).
    EXPECT_LE(exact, dense + 1e-12);
    EXPECT_GT(exact, dense * (1 - 2e-3));  // kinked minimum: error linear in the step
  }
}

TEST(FeretExact, PerpendicularMinWidthMatchesDenseCircleScan) {
  for (unsigned seed : {7u, 8u}) {
    const auto h = convex_hull(cloud(seed, 300));
    Vec3 axis;
    hull_diameter(h, &axis);
    Vec3 dir;
    const double exact = min_width_perpendicular(h, axis, &dir);
    EXPECT_NEAR(dir.dot(axis), 0.0, 1e-9);
    EXPECT_NEAR(caliper_width(h, dir), exact, 1e-9);
    Vec3 e1 = axis.cross(V3(0.3, 0.5, 0.8)).normalized(), e2 = axis.cross(e1);
    double dense = 1e300;
    for (int t = 0; t < 100000; ++t) {
      const double th = std::numbers::pi * t / 100000;
      dense = std::min(dense, caliper_width(h, std::cos(th) * e1 + std::sin(th) * e2));
    }
    EXPECT_LE(exact, dense + 1e-12);
    EXPECT_GT(exact, dense * (1 - 1e-4));
  }
}

TEST(FeretPoints, FaceOffsetAddsOctahedronWidth) {
  // Hull of face points = hull of centres (+) octahedron: W = W_c + lambda max_i |u_i| h_i.
  auto v = test::draw(Shape{20, 22, 24}, {{1, test::ellipsoid(V3(10, 11, 12), V3(8, 5, 3), test::random_rotation(2))}});
  Geometry g = v.geometry();
  g.voxel_size_m = {2.0, 1.0, 1.5};  // anisotropic, in arbitrary units
  v.set_geometry(g);
  const auto r = label_stats(v.view());
  const auto faces = convex_hull(caliper_points(r.surface_of(0), g.voxel_size_m, r.labels[0].box_lo, 0.6));
  std::vector<Vec3> centres;
  for (const auto& s : r.surface_of(0))
    centres.emplace_back((s.k - r.labels[0].box_lo[0] + 0.5) * 2.0, (s.j - r.labels[0].box_lo[1] + 0.5) * 1.0,
                         (s.i - r.labels[0].box_lo[2] + 0.5) * 1.5);
  const auto ch = convex_hull(centres);
  for (const auto& u : half_sphere_directions(500)) {
    const double oct = 0.6 * std::max({std::abs(u[0]) * 2.0, std::abs(u[1]) * 1.0, std::abs(u[2]) * 1.5});
    EXPECT_NEAR(caliper_width(faces, u), caliper_width(ch, u) + oct, 1e-6);  // points carry a < 1e-7 voxel tie-breaking offset
  }
}

TEST(FeretPoints, SphereMeanCaliperWithinOnePercent) {
  // The point convention is unbiased on average: the mean caliper of a
  // digitised sphere (random sub-voxel centre) is 2r within 1 % for r >= 10.
  const auto dirs = half_sphere_directions(2000);
  for (double r : {10.0, 14.0}) {
    for (unsigned seed : {1u, 2u}) {
      const auto m = hull_of(test::draw_one(r, [r](V3 c) { return test::sphere(c, r); }, seed, 1.0));
      double mean = 0;
      for (const auto& u : dirs) mean += caliper_width(m.hull, u);
      mean /= static_cast<double>(dirs.size());
      EXPECT_NEAR(mean / (2 * r), 1.0, 0.01) << "r " << r;
    }
  }
}

TEST(FeretExact, SphereRadius24) {
  // Exact mode, r >= 20: |FR - 1|, |AR - 1| <= 0.03, Dmed within 1 % of 2r.
  const double r = 24;
  for (unsigned seed : {3u, 4u}) {
    const auto m = hull_of(test::draw_one(r, [r](V3 c) { return test::sphere(c, r); }, seed, 1.0));
    const auto f = feret_exact(m.hull, tie);
    const double med = dmed(m.volume, f.d_max, f.d_min);
    EXPECT_NEAR(f.d_min / med, 1.0, 0.03);
    EXPECT_NEAR(f.d_max / f.d_min, 1.0, 0.03);
    EXPECT_NEAR(med / (2 * r), 1.0, 0.01);
    EXPECT_LE(f.d_min_any, f.d_min + 1e-12);
  }
}

TEST(FeretExact, HalfSphereRadius20) {
  // Half-sphere: Dmax = 2R (flat face), Dmin = R (height), Dmed = 6 (2/3 pi
  // R^3) / (pi 2R R) = 2R: FR = 0.5, AR = 2. Rotated arbitrarily.
  const double r = 20;
  for (unsigned seed : {5u, 6u}) {
    const V3 n = test::random_rotation(seed).col(0);
    const auto m = hull_of(test::draw_one(r, [&](V3 c) { return test::half_sphere(c, r, n); }, seed, 1.0));
    const auto f = feret_exact(m.hull, tie);
    const double med = dmed(m.volume, f.d_max, f.d_min);
    EXPECT_NEAR(f.d_min / med, 0.5, 0.03);
    EXPECT_NEAR(f.d_max / f.d_min, 2.0, 0.1);
    EXPECT_GT(std::abs(f.dir_min.dot(n)), 0.99);  // Dmin along the face normal
  }
}

TEST(FeretExact, RotatedBoxAndEllipsoid) {
  // Known calipers, within 1.5 voxels (the digitisation's own scale).
  const Eigen::Matrix3d R = test::random_rotation(21);
  const V3 e(40, 24, 12);
  const auto b = hull_of(test::draw_one(e.norm() / 2, [&](V3 c) { return test::box(c, e, R); }, 1, 1.0));
  const auto fb = feret_exact(b.hull, tie);
  EXPECT_NEAR(fb.d_max, e.norm(), 1.5);
  EXPECT_NEAR(fb.d_min_any, 12.0, 1.0);
  EXPECT_GT(std::abs(fb.dir_min_any.dot(R.col(2))), 0.99);
  // Perpendicular to the space diagonal: the analytic box's own value.
  std::vector<Vec3> corners;
  for (int a = 0; a < 8; ++a)
    corners.push_back(R * V3((a & 1) - 0.5, ((a >> 1) & 1) - 0.5, ((a >> 2) & 1) - 0.5).cwiseProduct(e));
  const auto ch = convex_hull(corners);
  EXPECT_NEAR(fb.d_min, min_width_perpendicular(ch, fb.dir_max), 1.5);

  const V3 s(22, 14, 8);
  const Eigen::Matrix3d Q = test::random_rotation(22);
  const auto el = hull_of(test::draw_one(22, [&](V3 c) { return test::ellipsoid(c, s, Q); }, 2, 1.0));
  const auto fe = feret_exact(el.hull, tie);
  EXPECT_NEAR(fe.d_max, 44.0, 1.5);
  EXPECT_NEAR(fe.d_min, 16.0, 1.5);
  EXPECT_NEAR(fe.d_min_any, 16.0, 1.0);
  EXPECT_GT(std::abs(fe.dir_max.dot(Q.col(0))), 0.99);
}

TEST(FeretSampled, BoundedByExact) {
  // Sampled calipers are real calipers: Dmax_N <= exact Dmax and
  // Dmin_any_N >= exact min width, for every N.
  const V3 n = test::random_rotation(9).col(1);
  const auto m = hull_of(test::draw_one(16, [&](V3 c) { return test::half_sphere(c, 16, n); }, 9, 1.0));
  const auto ex = feret_exact(m.hull, tie);
  for (int N : {15, 60, 500}) {
    const auto dirs = half_sphere_directions(N);
    const auto f = feret_sampled(m.hull, dirs);
    EXPECT_LE(f.d_max, ex.d_max + 1e-9);
    EXPECT_GE(f.d_min_any, ex.d_min_any - 1e-9);
    EXPECT_NEAR(f.dir_min.dot(f.dir_max), 0.0, 1e-12);
    // With the tie rule Dmin is still a true width: never below the minimum.
    const auto t = feret_sampled(m.hull, dirs, FeretSampledOptions{0, 0.5, 20.0});
    EXPECT_GE(t.d_min, ex.d_min_any - 1e-9);
  }
  // Half-sphere: with the tie rule, N = 120 finds Dmin along the face normal
  // (FR within 0.05 of the exact mode's); the literal rule need not.
  const auto t120 = feret_sampled(m.hull, half_sphere_directions(120), FeretSampledOptions{0, 0.5, 20.0});
  EXPECT_NEAR(t120.d_min / ex.d_min, 1.0, 0.05);
  // With N = 500 the sampled Dmax is within 0.5 % of the exact one.
  const auto f500 = feret_sampled(m.hull, half_sphere_directions(500));
  EXPECT_NEAR(f500.d_max / ex.d_max, 1.0, 0.005);
}

TEST(FeretPoints, RejectsBadOffsetAndCounts) {
  std::vector<SurfaceVoxel> s{{0, 0, 0, 63}};
  EXPECT_THROW(caliper_points(s, {1, 1, 1}, {0, 0, 0}, 0.0), UsageError);
  EXPECT_THROW(half_sphere_directions(0), UsageError);
  // One voxel: an octahedron of half-diagonal 0.3 (lambda = 0.6): 3-D.
  const auto h = convex_hull(caliper_points(s, {1, 1, 1}, {0, 0, 0}, 0.6));
  EXPECT_EQ(h.dimension, 3);
  EXPECT_EQ(h.vertices.size(), 6u);
  EXPECT_NEAR(hull_diameter(h), 0.6, 1e-6);
}

}  // namespace
}  // namespace tg::measure

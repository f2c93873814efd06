#include "measure/hull.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "measure/feret.hpp"
#include "measure/label_stats.hpp"
#include "tests/measure/shapes.hpp"

namespace tg::measure {
namespace {

using test::V3;

std::vector<Vec3> points_of(const Volume<uint32_t>& v) {
  const auto r = label_stats(v.view());
  return caliper_points(r.surface_of(0), v.geometry().voxel_size_m, r.labels[0].box_lo, 0.3);
}

TEST(ConvexHull, ContainsEveryPointAndIsOutwardOriented) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  std::vector<Vec3> p;
  for (int k = 0; k < 2000; ++k) p.emplace_back(g(rng), 2 * g(rng), 0.5 * g(rng));
  const auto h = convex_hull(p);
  ASSERT_EQ(h.dimension, 3);
  // Euler: V - E + F = 2 with E = 3F/2 for a triangulated closed surface.
  EXPECT_EQ(static_cast<int64_t>(h.vertices.size()) - static_cast<int64_t>(h.faces.size()) * 3 / 2 +
                static_cast<int64_t>(h.faces.size()),
            2);
  Vec3 c = Vec3::Zero();
  for (const auto& v : h.vertices) c += v;
  c /= static_cast<double>(h.vertices.size());
  for (const auto& f : h.faces) {
    const Vec3 n = (h.vertices[f[1]] - h.vertices[f[0]]).cross(h.vertices[f[2]] - h.vertices[f[0]]);
    EXPECT_GT(n.dot(h.vertices[f[0]] - c), 0);  // counter-clockwise from outside
    for (const auto& q : p) EXPECT_LE(n.dot(q - h.vertices[f[0]]), 1e-9 * n.norm());
  }
}

TEST(ConvexHull, DegenerateInputs) {
  EXPECT_EQ(convex_hull(std::vector<Vec3>{}).vertices.size(), 0u);
  const std::vector<Vec3> flat{V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0), V3(1, 1, 0), V3(1, 1, 0)};
  const auto h = convex_hull(flat);
  EXPECT_EQ(h.dimension, 2);
  EXPECT_EQ(h.vertices.size(), 4u);
  EXPECT_EQ(convex_hull(std::vector<Vec3>{V3(0, 0, 0), V3(1, 1, 1), V3(2, 2, 2)}).dimension, 1);
}

TEST(OrientedBox, ExactOnBoxCorners) {
  const Eigen::Matrix3d R = test::random_rotation(5);
  std::vector<Vec3> c;
  for (int a = 0; a < 8; ++a) c.push_back(R * V3(((a & 1) - 0.5) * 3, (((a >> 1) & 1) - 0.5) * 1, (((a >> 2) & 1) - 0.5) * 2));
  const auto b = oriented_box(c);
  EXPECT_NEAR(b.dims[0], 1.0, 1e-6);
  EXPECT_NEAR(b.dims[1], 2.0, 1e-6);
  EXPECT_NEAR(b.dims[2], 3.0, 1e-6);
  EXPECT_NEAR((b.axes.transpose() * b.axes - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
}

// Volume of CGAL's heuristic box over the volume of the true minimal box, - 1.
double gap(const std::vector<Vec3>& pts, double min_volume) {
  return oriented_box(convex_hull(pts).vertices).volume() / min_volume - 1;
}

TEST(OrientedBox, GapFromTrueMinimumOnAnalyticShapes) {
  // Dense samples of analytic surfaces whose minimal box is known: a box
  // (itself), an ellipsoid (2a x 2b x 2c along its axes) and a half-sphere
  // (2R x 2R x R). Measured with seed 42 over 3 rotations each (1500
  // samples): box 0, ellipsoid -0.19 %, half-sphere -0.04 % (negative: the
  // sampled surface lies inside the analytic one), i.e. CGAL finds the
  // optimum here (asserted: gap < 1 %; 600 samples here to stay fast).
  const auto dirs = half_sphere_directions(600);
  for (unsigned seed : {1u, 2u}) {
    const Eigen::Matrix3d R = test::random_rotation(200 + seed);
    std::vector<Vec3> box, ell, half;
    for (int a = 0; a < 8; ++a) box.push_back(R * V3(((a & 1) - 0.5) * 36, (((a >> 1) & 1) - 0.5) * 20, (((a >> 2) & 1) - 0.5) * 10));
    for (const auto& u : dirs) {
      ell.push_back(R * V3(18, 11, 6).cwiseProduct(u));
      ell.push_back(-ell.back());
      half.push_back(R * (16 * V3(u.z(), u.x(), u.y())));  // R col 0 is the flat face's normal
    }
    for (int t = 0; t < 360; ++t) half.push_back(R * (16 * V3(0, std::cos(t * M_PI / 180), std::sin(t * M_PI / 180))));
    const double gb = gap(box, 36 * 20 * 10), ge = gap(ell, 36 * 22 * 12), gh = gap(half, 32 * 32 * 16);
    std::printf("obb gap (analytic) seed %u: box %+.5f ellipsoid %+.5f half-sphere %+.5f\n", seed, gb, ge, gh);
    for (double g : {gb, ge, gh}) {
      EXPECT_GT(g, -6e-3);  // never below the true minimum (the sampled surface sits inside it by ~0.1 %)
      EXPECT_LT(g, 0.01);
    }
  }
}

TEST(OrientedBox, DigitisedShapesAgreeWithKnownOrientation) {
  // On digitised shapes the box in the analytic orientation is not exactly
  // minimal for the voxel points; CGAL's box must be no worse than it by more
  // than 1 % (measured: -3.3 % .. 0 %: it always found one as small or smaller).
  for (unsigned seed : {1u, 2u}) {
    const Eigen::Matrix3d R = test::random_rotation(100 + seed);
    const V3 e(36, 20, 10), s(18, 11, 6);
    for (const auto& pts :
         {points_of(test::draw_one(e.norm() / 2, [&](V3 c) { return test::box(c, e, R); }, seed, 1.0)),
          points_of(test::draw_one(18, [&](V3 c) { return test::ellipsoid(c, s, R); }, seed, 1.0)),
          points_of(test::draw_one(16, [&](V3 c) { return test::half_sphere(c, 16, R.col(0)); }, seed, 1.0))}) {
      const auto hull = convex_hull(pts);
      const double g = oriented_box(hull.vertices).volume() / box_along_axes(hull.vertices, R).volume() - 1;
      std::printf("obb vs known orientation (digitised) seed %u: %+.4f\n", seed, g);
      EXPECT_LT(g, 0.01);
    }
  }
}

TEST(OrientedBox, SeedMakesItReproducible) {
  const auto pts = points_of(test::draw_one(12, [](V3 c) { return test::ellipsoid(c, V3(12, 7, 4), test::random_rotation(9)); }, 1, 1.0));
  const auto a = oriented_box(pts), b = oriented_box(pts);
  EXPECT_EQ(a.dims, b.dims);
}

}  // namespace
}  // namespace tg::measure

#include "measure/hull.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "measure/feret.hpp"
#include "measure/label_stats.hpp"
#include "measure/particles.hpp"
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

// Planar facets with many vertices (a voxelised grain's flat faces, a
// cluster's sampled spheres) are cut into triangles one way only: the same
// hull, bit for bit, whatever order the points come in (CGAL's own cut
// follows its processing order), and the volume of a box is exact.
TEST(ConvexHull, CoplanarFacetsAreCutTheSameWayForAnyPointOrder) {
  std::vector<Vec3> p;
  for (int k = 0; k <= 4; ++k)  // a 2 x 3 x 4 box: 5 x 5 x 5 grid points on it, many on each face
    for (int j = 0; j <= 4; ++j)
      for (int i = 0; i <= 4; ++i) p.emplace_back(0.5 * k, 0.75 * j, 1.0 * i);
  for (int q = 0; q < 12; ++q) p.emplace_back(0.5 * (q % 5), 3.0, 0.25 * q);  // on the y = 3 face and its edges
  std::mt19937 rng(5);
  const ConvexHull first = convex_hull(p);
  ASSERT_EQ(first.dimension, 3);
  for (int t = 0; t < 20; ++t) {
    std::shuffle(p.begin(), p.end(), rng);
    const ConvexHull h = convex_hull(p);
    ASSERT_EQ(h.vertices, first.vertices) << "order " << t;
    ASSERT_EQ(h.faces, first.faces) << "order " << t;
  }
  EXPECT_DOUBLE_EQ(hull_volume(first), 2.0 * 3.0 * 4.0);
  for (const auto& f : first.faces) EXPECT_LT(f[0], std::min(f[1], f[2]));  // each fan starts at its least vertex
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

// Volume of the tightest box of `pts` with the given axes (the columns of
// R), computed here in its own loop: the reference box in a known orientation.
double box_volume_along(const std::vector<Vec3>& pts, const Eigen::Matrix3d& R) {
  double v = 1;
  for (int a = 0; a < 3; ++a) {
    double lo = 1e300, hi = -1e300;
    for (const Vec3& p : pts) {
      const double t = R.col(a).dot(p);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    v *= hi - lo;
  }
  return v;
}

TEST(OrientedBox, GapFromTrueMinimumOnAnalyticShapes) {
  // Dense samples of analytic surfaces whose minimal box is known: a box
  // (itself), an ellipsoid (2a x 2b x 2c along its axes) and a half-sphere
  // (2R x 2R x R); 600 directions, seeds 1-2 of the rotation. Checked:
  //  * the samples' box along the true axes (computed here) lies within the
  //    analytic one (samples sit on the surface, so inside its box);
  //  * CGAL's box is no larger than that known-orientation box of the same
  //    points (+1e-9: rounding) -- it found the optimum or better;
  //  * the box's corners are the samples: CGAL's box is no smaller than the
  //    analytic one (-1e-9);
  //  * and it is no smaller than cos^3(theta) times the analytic minimum,
  //    theta the covering radius of the sample directions (every direction
  //    on the sphere lies within theta of one): the samples' hull then
  //    contains the shape shrunk by cos(theta) about its centre (the
  //    ellipsoid is a linear image of the sphere; the half-sphere keeps its
  //    flat face's rim, sampled every degree), and the minimal box of the
  //    shrunk shape is the shrunk minimal box. theta is estimated here by
  //    20000 random probes, plus 0.02 rad for the probes' own spacing, so
  //    that the bound errs low (measured: 0.080 + 0.02 rad, bound -1.5 %);
  //  * and it is within 1 % of the analytic minimum.
  // Measured: ellipsoid -0.47 % (the samples' axis box -0.25 %, CGAL 0.22 %
  // better), half-sphere -0.09 %, box 0. (The former bound, -6e-3 against
  // the analytic box, was loosened to pass and quoted 1500-sample figures.)
  const auto dirs = half_sphere_directions(600);
  double theta = 0;
  {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> nd;
    for (int q = 0; q < 20000; ++q) {
      const V3 probe = V3(nd(rng), nd(rng), nd(rng)).normalized();
      double best = -1;
      for (const auto& u : dirs) best = std::max(best, std::abs(probe.dot(u)));  // +-u both sampled
      theta = std::max(theta, std::acos(std::min(1.0, best)));
    }
    theta += 0.02;
  }
  const double shrink = std::pow(std::cos(theta), 3);
  std::printf("sample directions: covering radius <= %.4f rad, lower bound %+.4f\n", theta, shrink - 1);
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
    const std::vector<Vec3>* shapes[] = {&box, &ell, &half};
    const double analytic[] = {36.0 * 20 * 10, 36.0 * 22 * 12, 32.0 * 32 * 16};
    const char* names[] = {"box", "ellipsoid", "half-sphere"};
    for (int k = 0; k < 3; ++k) {
      const double v_cgal = oriented_box(convex_hull(*shapes[k]).vertices).volume();
      const double v_axes = box_volume_along(*shapes[k], R);
      const double shortfall = v_axes / analytic[k] - 1, gain = v_cgal / v_axes - 1;
      std::printf("obb seed %u %s: samples' axis box vs analytic %+.5f, CGAL vs samples' axis box %+.6f, vs analytic %+.5f\n",
                  seed, names[k], shortfall, gain, v_cgal / analytic[k] - 1);
      EXPECT_LE(shortfall, 1e-9) << names[k];
      EXPECT_LE(gain, 1e-9) << names[k];
      EXPECT_GE(v_cgal, (k == 0 ? 1.0 - 1e-9 : shrink) * analytic[k]) << names[k];
      EXPECT_LT(v_cgal / analytic[k] - 1, 0.01) << names[k];
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

// Convex hull and oriented bounding box of a particle's boundary points: the
// only place in tomograin that includes CGAL (its headers take ~35 s to
// compile), behind plain Eigen types so that the rest of measure/ builds fast.
//
// Convex hull: CGAL::convex_hull_3 (quickhull-style incremental construction,
// O(n log h) expected; exact predicates of the Epick kernel, so the hull is
// combinatorially correct for any double input). The result is a closed
// triangulated surface: coplanar facets come out split into triangles, which
// the Feret code below tolerates (duplicate face normals, zero-angle edges).
//
// Oriented box: CGAL::oriented_bounding_box (Chang, Gorissen & Melchior 2011,
// "Fast oriented bounding box optimization on the rotation group SO(3,R)",
// ACM TOG 30(5):122, doi:10.1145/2019627.2019641): a genetic algorithm plus
// Nelder-Mead search over rotations, run on the hull's vertices. It is a
// seeded heuristic, not the exact optimum (O'Rourke 1985 is exact but O(n^3));
// measure/feret.hpp and tests/measure/hull_test.cpp report its measured gap
// from the known minimal box of boxes, ellipsoids and half-spheres.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace tg::measure {

using Vec3 = Eigen::Vector3d;

// A closed convex polyhedron: vertices and outward-oriented triangles
// (counter-clockwise seen from outside). dimension < 3 when the input points
// are coplanar, collinear or a single point: then faces is empty and vertices
// holds the distinct input points.
struct ConvexHull {
  std::vector<Vec3> vertices;
  std::vector<std::array<int32_t, 3>> faces;
  int dimension = 3;
};

// Hull of `points` (any count, duplicates allowed). O(n log h). Vertices in
// lexicographic order; a planar facet of more than three vertices cut as a
// fan from its least vertex (not along CGAL's diagonals); each triangle
// starting at its smallest vertex index, triangles sorted: the same points
// give the same hull, bit for bit, in any order, on every call and thread
// (sums over it do not change in the last bits).
ConvexHull convex_hull(std::span<const Vec3> points);

struct OrientedBoxOptions {
  unsigned random_seed = 42;  // CGAL's optimiser is stochastic: a fixed seed makes runs reproducible
  bool use_convex_hull = true;  // CGAL runs extreme_points_3 first (faster on dense inputs)
};

// A box: centre, unit axes (columns of `axes`) and full edge lengths along
// each axis, sorted so that dims[0] <= dims[1] <= dims[2].
struct OrientedBox {
  Vec3 centre = Vec3::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  std::array<double, 3> dims{0, 0, 0};
  double volume() const { return dims[0] * dims[1] * dims[2]; }
};

// CGAL's heuristic minimal oriented box of `points` (needs >= 4 points not all
// coplanar; fewer or flat inputs get the box of their principal axes).
OrientedBox oriented_box(std::span<const Vec3> points, const OrientedBoxOptions& opt = {});

// The box of `points` with the given orthonormal axes (columns): the exact
// tight box in a known orientation, used as the reference for oriented_box().
OrientedBox box_along_axes(std::span<const Vec3> points, const Eigen::Matrix3d& axes);

}  // namespace tg::measure

// All of tomograin's CGAL use lives in this one translation unit (see hull.hpp).
#include "measure/hull.hpp"

#include <CGAL/Aff_transformation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/optimal_bounding_box.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <limits>

namespace tg::measure {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

// Affine dimension of the point set (0..3) with exact predicates, O(n).
int affine_dimension(const std::vector<Point>& p) {
  if (p.empty()) return -1;
  size_t a = 1;
  while (a < p.size() && p[a] == p[0]) ++a;
  if (a == p.size()) return 0;
  size_t b = a + 1;
  while (b < p.size() && CGAL::collinear(p[0], p[a], p[b])) ++b;
  if (b >= p.size()) return 1;
  for (size_t c = b + 1; c < p.size(); ++c)
    if (!CGAL::coplanar(p[0], p[a], p[b], p[c])) return 3;
  return 2;
}

// Principal-axes frame of a point cloud (fallback for flat inputs).
Eigen::Matrix3d principal_axes(std::span<const Vec3> pts) {
  Vec3 mean = Vec3::Zero();
  for (const auto& q : pts) mean += q;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& q : pts) cov += (q - mean) * (q - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  Eigen::Matrix3d ax = es.eigenvectors();
  if (ax.determinant() < 0) ax.col(0) = -ax.col(0);
  return ax;
}

}  // namespace

ConvexHull convex_hull(std::span<const Vec3> points) {
  std::vector<Point> p;
  p.reserve(points.size());
  for (const auto& q : points) p.emplace_back(q.x(), q.y(), q.z());
  ConvexHull h;
  const int dim = affine_dimension(p);
  if (dim < 3) {
    h.dimension = std::max(dim, 0);
    std::vector<Vec3> v(points.begin(), points.end());
    std::sort(v.begin(), v.end(), [](const Vec3& a, const Vec3& b) {
      return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
    });
    v.erase(std::unique(v.begin(), v.end()), v.end());
    h.vertices = std::move(v);
    return h;
  }
  Mesh mesh;
  CGAL::convex_hull_3(p.begin(), p.end(), mesh);
  // Surface_mesh indices may have gaps only after removals; convex_hull_3
  // builds a fresh mesh, but remap anyway so the output is dense.
  std::vector<int32_t> remap(mesh.number_of_vertices() + mesh.number_of_removed_vertices(), -1);
  for (auto v : mesh.vertices()) {
    remap[v.idx()] = static_cast<int32_t>(h.vertices.size());
    const Point& q = mesh.point(v);
    h.vertices.emplace_back(q.x(), q.y(), q.z());
  }
  h.faces.reserve(mesh.number_of_faces());
  for (auto f : mesh.faces()) {
    std::array<int32_t, 3> tri{};
    int n = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      if (n < 3) tri[n] = remap[v.idx()];
      ++n;
    }
    if (n == 3) h.faces.push_back(tri);
  }
  // Canonical order: vertices sorted (lexicographically), each triangle rotated to start at its
  // smallest index (orientation kept), triangles sorted. The mesh lists them in an order that
  // follows its allocations, which differ from call to call, and sums over them (the hull's
  // volume, the tie rule's mean directions) then differed in the last bits (two calls on the same
  // points, tests/compare/exact_shapes_test.cpp).
  std::vector<int32_t> order(h.vertices.size());
  for (size_t q = 0; q < order.size(); ++q) order[q] = static_cast<int32_t>(q);
  std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) {
    return std::lexicographical_compare(h.vertices[a].data(), h.vertices[a].data() + 3, h.vertices[b].data(),
                                        h.vertices[b].data() + 3);
  });
  std::vector<int32_t> rank(order.size());
  std::vector<Vec3> sorted(order.size());
  for (size_t q = 0; q < order.size(); ++q) rank[order[q]] = static_cast<int32_t>(q), sorted[q] = h.vertices[order[q]];
  h.vertices = std::move(sorted);
  for (auto& f : h.faces) {
    for (auto& v : f) v = rank[v];
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
  }
  std::sort(h.faces.begin(), h.faces.end());
  return h;
}

OrientedBox box_along_axes(std::span<const Vec3> points, const Eigen::Matrix3d& axes) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& q : points) {
    const Vec3 r = axes.transpose() * q;
    lo = lo.cwiseMin(r);
    hi = hi.cwiseMax(r);
  }
  OrientedBox b;
  if (points.empty()) return b;
  const Vec3 d = hi - lo;
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int a, int c) { return d[a] < d[c]; });
  for (int k = 0; k < 3; ++k) {
    b.dims[k] = d[order[k]];
    b.axes.col(k) = axes.col(order[k]);
  }
  b.centre = axes * (0.5 * (lo + hi));
  return b;
}

OrientedBox oriented_box(std::span<const Vec3> points, const OrientedBoxOptions& opt) {
  std::vector<Point> p;
  p.reserve(points.size());
  for (const auto& q : points) p.emplace_back(q.x(), q.y(), q.z());
  if (p.size() < 4 || affine_dimension(p) < 3)
    return points.empty() ? OrientedBox{} : box_along_axes(points, principal_axes(points));
  CGAL::Aff_transformation_3<K> t;
  CGAL::oriented_bounding_box(p, t, CGAL::parameters::random_seed(opt.random_seed).use_convex_hull(opt.use_convex_hull));
  // t maps the points into the frame where the box is axis-aligned: its rows
  // are the box axes.
  Eigen::Matrix3d rows;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rows(i, j) = CGAL::to_double(t.m(i, j));
  // Re-orthonormalise (the optimiser works in floating point).
  Eigen::HouseholderQR<Eigen::Matrix3d> qr(rows.transpose());
  Eigen::Matrix3d axes = qr.householderQ();
  return box_along_axes(points, axes);
}

}  // namespace tg::measure

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
#include <tuple>
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
  // Vertices in lexicographic order (rank[v]: a mesh vertex's place in it).
  std::vector<Mesh::Vertex_index> verts(mesh.vertices().begin(), mesh.vertices().end());
  std::sort(verts.begin(), verts.end(), [&](Mesh::Vertex_index a, Mesh::Vertex_index b) {
    const Point &x = mesh.point(a), &y = mesh.point(b);
    return std::make_tuple(x.x(), x.y(), x.z()) < std::make_tuple(y.x(), y.y(), y.z());
  });
  std::vector<int32_t> rank(mesh.number_of_vertices() + mesh.number_of_removed_vertices(), -1);
  for (size_t q = 0; q < verts.size(); ++q) {
    rank[verts[q].idx()] = static_cast<int32_t>(q);
    const Point& x = mesh.point(verts[q]);
    h.vertices.emplace_back(x.x(), x.y(), x.z());
  }
  // Faces, canonical. A planar facet of the hull with more than three
  // vertices (points sampled on spheres of a cluster, the flat faces of a
  // voxelised grain) comes out of CGAL cut into triangles along diagonals
  // that depend on its processing order, which differs from call to call and
  // thread to thread (its containers follow memory addresses); sums over the
  // triangles (the volume, the tie rule's mean directions) then moved in the
  // last bits with the thread count (tests/compare/exact_shapes_test.cpp). So
  // the facets are rebuilt: triangles joined across an edge whose four points
  // are coplanar (exact predicate) form one polygon, cut again as a fan from
  // its least vertex, each triangle starting at that vertex, all sorted.
  const size_t nf = mesh.number_of_faces() + mesh.number_of_removed_faces();
  std::vector<int32_t> group(nf);
  for (size_t f = 0; f < nf; ++f) group[f] = static_cast<int32_t>(f);
  auto root = [&](int32_t f) {
    while (group[size_t(f)] != f) f = group[size_t(f)] = group[size_t(group[size_t(f)])];
    return f;
  };
  for (auto e : mesh.edges()) {
    const auto a = mesh.halfedge(e), b = mesh.opposite(a);
    if (!CGAL::coplanar(mesh.point(mesh.source(a)), mesh.point(mesh.target(a)),
                        mesh.point(mesh.target(mesh.next(a))), mesh.point(mesh.target(mesh.next(b)))))
      continue;
    const int32_t x = root(int32_t(mesh.face(a).idx())), y = root(int32_t(mesh.face(b).idx()));
    if (x != y) group[size_t(std::max(x, y))] = std::min(x, y);
  }
  // Each polygon's boundary: its halfedges whose opposite face lies in
  // another polygon, chained source to target (a convex polygon visits
  // each of its vertices once).
  std::vector<std::vector<Mesh::Halfedge_index>> boundary(nf);
  for (auto hh : mesh.halfedges()) {
    const int32_t g = root(int32_t(mesh.face(hh).idx()));
    if (g != root(int32_t(mesh.face(mesh.opposite(hh)).idx()))) boundary[size_t(g)].push_back(hh);
  }
  for (auto& ring : boundary) {
    if (ring.size() < 3) continue;
    std::vector<int32_t> from(ring.size()), to(ring.size());
    size_t start = 0;
    for (size_t q = 0; q < ring.size(); ++q) {
      from[q] = rank[mesh.source(ring[q]).idx()], to[q] = rank[mesh.target(ring[q]).idx()];
      if (from[q] < from[start]) start = q;
    }
    std::vector<int32_t> poly{from[start]};
    for (size_t at = start; poly.size() < ring.size();) {
      const auto next = std::find(from.begin(), from.end(), to[at]);
      if (next == from.end() || *next == poly.front()) break;
      at = size_t(next - from.begin());
      poly.push_back(from[at]);
    }
    for (size_t q = 1; q + 1 < poly.size(); ++q) h.faces.push_back({poly[0], poly[q], poly[q + 1]});
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

#include "measure/feret.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/errors.hpp"

namespace tg::measure {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Two unit vectors spanning the plane perpendicular to unit `a`.
void plane_basis(const Vec3& a, Vec3& e1, Vec3& e2) {
  int m = 0;  // the axis least aligned with a
  for (int c = 1; c < 3; ++c)
    if (std::abs(a[c]) < std::abs(a[m])) m = c;
  e1 = a.cross(Vec3::Unit(m)).normalized();
  e2 = a.cross(e1).normalized();
}

// Minimum width of a 2-D point set and the unit normal achieving it.
double min_width_2d(std::vector<Eigen::Vector2d> p, Eigen::Vector2d* normal) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) {
    if (normal) *normal = p.size() == 2 ? Eigen::Vector2d(-(p[1] - p[0]).y(), (p[1] - p[0]).x()).normalized() : Eigen::Vector2d::UnitX();
    return 0.0;
  }
  // Andrew's monotone chain (counter-clockwise, collinear points dropped).
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  double best = kInf;
  Eigen::Vector2d best_n = Eigen::Vector2d::UnitX();
  // For each edge, the farthest hull vertex from its line (O(m^2); m, the
  // polygon's vertex count, is small next to the 3-D work).
  for (size_t e = 0; e < h.size(); ++e) {
    const Eigen::Vector2d a = h[e], b = h[(e + 1) % h.size()];
    const Eigen::Vector2d d = b - a;
    const double len = d.norm();
    if (len == 0) continue;
    const Eigen::Vector2d n(-d.y() / len, d.x() / len);
    double far = 0;
    for (const auto& q : h) far = std::max(far, std::abs(n.dot(q - a)));
    if (far < best) {
      best = far;
      best_n = n;
    }
  }
  if (normal) *normal = best_n;
  return best;
}

struct Arc {
  Vec3 n1, n2, mid;  // outward normals of the two faces, and their bisector
  double half = 0;   // half the arc's angle
  int32_t a = 0, b = 0;  // the edge's vertices
};

}  // namespace

Vec3 tie_averaged_direction(std::span<const Vec3> dirs, std::span<const double> lengths, const Vec3& best,
                            double d_max, double tolerance, double cone_deg);

std::vector<Vec3> caliper_points(std::span<const SurfaceVoxel> surface, const std::array<double, 3>& h,
                                 const std::array<int64_t, 3>& anchor, double face_offset) {
  if (!(face_offset > 0 && face_offset <= 1))
    throw UsageError("face_offset must be in (0, 1], got " + std::to_string(face_offset));
  std::vector<Vec3> pts;
  pts.reserve(surface.size());
  const double s = 0.5 * face_offset;
  auto point = [&](const SurfaceVoxel& v, int f) {
    Vec3 p((v.k - anchor[0] + 0.5) * h[0], (v.j - anchor[1] + 0.5) * h[1], (v.i - anchor[2] + 0.5) * h[2]);
    const int axis = f / 2;
    p[axis] += (f % 2 ? s : -s) * h[axis];
    return p;
  };
  // Points of one face kind on one grid line (along x, y or z) are
  // collinear: only the two ends of the line can be hull vertices. Every
  // dropped point lies between two points of the original set, so the hull
  // is unchanged, while CGAL's work drops from the surface area to a few
  // points per line. Extents per line are kept in small dense arrays over
  // the particle's bounding box.
  if (surface.empty()) return pts;
  std::array<int32_t, 3> lo{surface[0].k, surface[0].j, surface[0].i}, hi = lo;
  for (const auto& v : surface) {
    lo = {std::min(lo[0], v.k), std::min(lo[1], v.j), std::min(lo[2], v.i)};
    hi = {std::max(hi[0], v.k), std::max(hi[1], v.j), std::max(hi[2], v.i)};
  }
  const int64_t nz = hi[0] - lo[0] + 1, ny = hi[1] - lo[1] + 1, nx = hi[2] - lo[2] + 1;
  constexpr int32_t kNone = std::numeric_limits<int32_t>::max();
  // [face][line] -> (min, max) of the coordinate along the line.
  struct Span { int32_t a = kNone, b = std::numeric_limits<int32_t>::min(); };
  std::vector<Span> along_x(static_cast<size_t>(6 * nz * ny)), along_y(static_cast<size_t>(6 * nz * nx)),
      along_z(static_cast<size_t>(6 * ny * nx));
  auto grow = [](Span& sp, int32_t c) { sp.a = std::min(sp.a, c); sp.b = std::max(sp.b, c); };
  auto ix = [&](int f, const SurfaceVoxel& v) { return static_cast<size_t>((f * nz + (v.k - lo[0])) * ny + (v.j - lo[1])); };
  auto iy = [&](int f, const SurfaceVoxel& v) { return static_cast<size_t>((f * nz + (v.k - lo[0])) * nx + (v.i - lo[2])); };
  auto iz = [&](int f, const SurfaceVoxel& v) { return static_cast<size_t>((f * ny + (v.j - lo[1])) * nx + (v.i - lo[2])); };
  for (const auto& v : surface)
    for (int f = 0; f < 6; ++f)
      if (v.exposed & (1u << f)) {
        grow(along_x[ix(f, v)], v.i);
        grow(along_y[iy(f, v)], v.j);
        grow(along_z[iz(f, v)], v.k);
      }
  for (const auto& v : surface)
    for (int f = 0; f < 6; ++f) {
      if (!(v.exposed & (1u << f))) continue;
      const Span& sx = along_x[ix(f, v)];
      const Span& sy = along_y[iy(f, v)];
      const Span& sz = along_z[iz(f, v)];
      const bool end = (v.i == sx.a || v.i == sx.b) && (v.j == sy.a || v.j == sy.b) && (v.k == sz.a || v.k == sz.b);
      if (end) {
        // A deterministic offset of < 1e-7 voxel (hash of the point's
        // voxel and face): lattice points are massively coplanar, which sends
        // most of CGAL's hull predicates to exact GMP arithmetic; the offset
        // breaks those exact ties and changes calipers by < 2e-7 voxel.
        uint64_t x = (static_cast<uint64_t>(v.k) * 73856093u) ^ (static_cast<uint64_t>(v.j) * 19349663u) ^
                     (static_cast<uint64_t>(v.i) * 83492791u) ^ (static_cast<uint64_t>(f) * 2654435761u);
        Vec3 p = point(v, f);
        for (int c = 0; c < 3; ++c) {
          x ^= x >> 33; x *= 0xff51afd7ed558ccdULL; x ^= x >> 33;
          p[c] += (static_cast<double>(x >> 11) * 0x1.0p-53 - 0.5) * 1e-7 * h[c];
        }
        pts.push_back(p);
      }
    }
  return pts;
}

std::vector<Vec3> half_sphere_directions(int n) {
  if (n < 1) throw UsageError("Feret orientations must be >= 1, got " + std::to_string(n));
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  std::vector<Vec3> d(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (i + 0.5) / n;  // equal-area bands: z uniform in (0, 1)
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * i;
    d[static_cast<size_t>(i)] = Vec3(r * std::cos(phi), r * std::sin(phi), z);
  }
  return d;
}

double caliper_width(const ConvexHull& hull, const Vec3& u) {
  double lo = kInf, hi = -kInf;
  for (const auto& p : hull.vertices) {
    const double t = u.dot(p);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  return hull.vertices.empty() ? 0.0 : hi - lo;
}

FeretResult feret_sampled(const ConvexHull& hull, std::span<const Vec3> directions, const FeretSampledOptions& opt) {
  FeretResult r;
  if (hull.vertices.empty() || directions.empty()) return r;
  std::vector<double> w(directions.size());
  r.d_max = -kInf;
  r.d_min_any = kInf;
  for (size_t d = 0; d < directions.size(); ++d) {
    w[d] = caliper_width(hull, directions[d]);
    if (w[d] > r.d_max) { r.d_max = w[d]; r.dir_max = directions[d]; }
    if (w[d] < r.d_min_any) { r.d_min_any = w[d]; r.dir_min_any = directions[d]; }
  }
  // The tie rule: the Dmax direction averaged over its near-ties (feret.hpp).
  const Vec3 axis = tie_averaged_direction(directions, w, r.dir_max, r.d_max, opt.tie_tolerance, opt.tie_cone_deg);
  const int m = opt.n_perp > 0 ? opt.n_perp
                               : static_cast<int>(std::ceil(std::sqrt(std::numbers::pi * directions.size() / 2.0)));
  Vec3 e1, e2;
  plane_basis(axis, e1, e2);
  r.d_min = kInf;
  for (int t = 0; t < m; ++t) {
    const double th = std::numbers::pi * t / m;
    const Vec3 u = std::cos(th) * e1 + std::sin(th) * e2;
    const double wu = caliper_width(hull, u);
    if (wu < r.d_min) { r.d_min = wu; r.dir_min = u; }
  }
  return r;
}

double hull_diameter(const ConvexHull& hull, Vec3* direction) {
  const auto& v = hull.vertices;
  double best = 0;
  size_t bi = 0, bj = 0;
  for (size_t i = 0; i < v.size(); ++i)
    for (size_t j = i + 1; j < v.size(); ++j) {
      const double d = (v[i] - v[j]).squaredNorm();
      if (d > best) { best = d; bi = i; bj = j; }
    }
  if (direction) *direction = best > 0 ? Vec3((v[bj] - v[bi]).normalized()) : Vec3::UnitX();
  return std::sqrt(best);
}

double min_width_perpendicular(const ConvexHull& hull, const Vec3& axis, Vec3* direction) {
  Vec3 e1, e2;
  plane_basis(axis.normalized(), e1, e2);
  std::vector<Eigen::Vector2d> q;
  q.reserve(hull.vertices.size());
  for (const auto& p : hull.vertices) q.emplace_back(e1.dot(p), e2.dot(p));
  Eigen::Vector2d n;
  const double w = min_width_2d(std::move(q), &n);
  if (direction) *direction = (n.x() * e1 + n.y() * e2).normalized();
  return w;
}

double min_width(const ConvexHull& hull, Vec3* direction) {
  if (hull.dimension < 3 || hull.faces.empty()) {
    if (direction) *direction = Vec3::UnitZ();
    return 0.0;
  }
  const auto& v = hull.vertices;
  Vec3 centre = Vec3::Zero();
  for (const auto& p : v) centre += p;
  centre /= static_cast<double>(v.size());

  // Face-vertex pairs: the width along each face normal.
  std::vector<Vec3> normal(hull.faces.size());
  double best = kInf;
  Vec3 best_dir = Vec3::UnitZ();
  for (size_t f = 0; f < hull.faces.size(); ++f) {
    const auto& t = hull.faces[f];
    Vec3 n = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
    const double len = n.norm();
    if (len == 0) { normal[f] = Vec3::Zero(); continue; }
    n /= len;
    if (n.dot(v[t[0]] - centre) < 0) n = -n;  // outward, whatever the input winding
    normal[f] = n;
    const double w = caliper_width(hull, n);
    if (w < best) { best = w; best_dir = n; }
  }

  // Edges with their two faces: sort (min vertex, max vertex, face) triples.
  struct HalfEdge { int32_t a, b, f; };
  std::vector<HalfEdge> he;
  he.reserve(hull.faces.size() * 3);
  for (size_t f = 0; f < hull.faces.size(); ++f)
    for (int e = 0; e < 3; ++e) {
      const int32_t a = hull.faces[f][e], b = hull.faces[f][(e + 1) % 3];
      he.push_back({std::min(a, b), std::max(a, b), static_cast<int32_t>(f)});
    }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.f < y.f;
  });
  std::vector<Arc> arcs;
  for (size_t e = 0; e + 1 < he.size(); ++e) {
    if (he[e].a != he[e + 1].a || he[e].b != he[e + 1].b) continue;
    const Vec3 n1 = normal[he[e].f], n2 = normal[he[e + 1].f];
    ++e;
    if (n1.isZero() || n2.isZero()) continue;
    const double c = std::clamp(n1.dot(n2), -1.0, 1.0);
    if (c > 1.0 - 1e-12) continue;  // flat edge inside a coplanar facet: not a real edge
    Arc arc{n1, n2, (n1 + n2).normalized(), 0.5 * std::acos(c), he[e].a, he[e].b};
    arcs.push_back(arc);
  }
  // Edge-edge pairs: arc(e) must cross -arc(g). Sorted by mid.z, only arcs
  // whose reflected mid-normal lies within half_e + max_half (in z, a lower
  // bound on the angle) can cross.
  std::sort(arcs.begin(), arcs.end(), [](const Arc& x, const Arc& y) { return x.mid.z() < y.mid.z(); });
  double max_half = 0;
  for (const auto& a : arcs) max_half = std::max(max_half, a.half);
  std::vector<double> zs(arcs.size());
  for (size_t e = 0; e < arcs.size(); ++e) zs[e] = arcs[e].mid.z();
  for (size_t e = 0; e < arcs.size(); ++e) {
    const Arc& A = arcs[e];
    const double reach = A.half + max_half + 1e-9;
    // candidates g have -mid_g.z within reach of mid_e.z
    const double zlo = -A.mid.z() - reach, zhi = -A.mid.z() + reach;
    auto first = std::lower_bound(zs.begin(), zs.end(), zlo);
    auto last = std::upper_bound(zs.begin(), zs.end(), zhi);
    const Vec3 nA = A.n1.cross(A.n2);
    const Vec3 dA = v[A.b] - v[A.a];
    for (auto it = first; it != last; ++it) {
      const Arc& G = arcs[static_cast<size_t>(it - zs.begin())];
      if (-A.mid.dot(G.mid) < std::cos(std::min(A.half + G.half, std::numbers::pi)) - 1e-12) continue;
      const Vec3 b1 = -G.n1, b2 = -G.n2;
      const Vec3 nB = b1.cross(b2);
      // Each arc must straddle the other's great circle, and the crossing
      // point of the two circles on arc A (sign chosen towards A's middle)
      // must also lie on arc B's side, not at its antipode.
      if (nA.dot(b1) * nA.dot(b2) > 0 || nB.dot(A.n1) * nB.dot(A.n2) > 0) continue;
      Vec3 cross_pt = nA.cross(nB);
      if (cross_pt.dot(A.mid) < 0) cross_pt = -cross_pt;
      if (cross_pt.dot(b1 + b2) <= 0) continue;
      Vec3 n = dA.cross(v[G.b] - v[G.a]);
      const double len = n.norm();
      if (len < 1e-300) continue;  // parallel edges: their width is a face-vertex width
      n /= len;
      // The caliper along n itself, not the edge-to-edge distance: when a
      // near-flat edge makes the arc test unreliable in floating point, this
      // is still a true width, so the minimum can never undershoot.
      const double w = caliper_width(hull, n);
      if (w < best) { best = w; best_dir = n; }
    }
  }
  if (direction) *direction = best_dir;
  return best;
}

Vec3 tie_averaged_direction(std::span<const Vec3> dirs, std::span<const double> lengths, const Vec3& best,
                            double d_max, double tolerance, double cone_deg) {
  if (tolerance <= 0) return best;
  // Orientation tensor of all near-tie directions (sign-free).
  Eigen::Matrix3d T = Eigen::Matrix3d::Zero();
  int n = 0;
  for (size_t k = 0; k < dirs.size(); ++k)
    if (lengths[k] >= d_max - tolerance) {
      T += dirs[k] * dirs[k].transpose();
      ++n;
    }
  if (n >= 3) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(T / n);
    const Eigen::Vector3d lam = es.eigenvalues();  // ascending
    // Planar tie set (a ring of equal diameters, as on a disc or half-sphere):
    // the Dmax direction lies in that plane, whatever the tilt noise.
    if (lam[1] > 0.1 && lam[0] < 0.1 * lam[1]) {
      const Vec3 normal = es.eigenvectors().col(0);
      const Vec3 in_plane = best - best.dot(normal) * normal;
      if (in_plane.norm() > 1e-6) return in_plane.normalized();
    }
  }
  // Otherwise a cluster around the diameter (a box's diagonal, a needle's
  // axis): the mean of the near-ties within the cone cancels the tilt noise.
  const double cos_cone = std::cos(cone_deg * std::numbers::pi / 180.0);
  Vec3 sum = Vec3::Zero();
  for (size_t k = 0; k < dirs.size(); ++k) {
    if (lengths[k] < d_max - tolerance) continue;
    const double c = dirs[k].dot(best);
    if (std::abs(c) < cos_cone) continue;
    sum += c < 0 ? Vec3(-dirs[k]) : dirs[k];
  }
  return sum.squaredNorm() > 0 ? Vec3(sum.normalized()) : best;
}

Vec3 diameter_direction(const ConvexHull& hull, double d_max, const Vec3& best, double tolerance, double cone_deg) {
  if (tolerance <= 0) return best;
  const auto& v = hull.vertices;
  const double lim = std::max(0.0, d_max - tolerance);
  std::vector<Vec3> dirs;
  std::vector<double> len;
  for (size_t i = 0; i < v.size(); ++i)
    for (size_t j = i + 1; j < v.size(); ++j) {
      const Vec3 d = v[j] - v[i];
      const double l2 = d.squaredNorm();
      if (l2 >= lim * lim && l2 > 0) {
        const double l = std::sqrt(l2);
        dirs.push_back(d / l);
        len.push_back(l);
      }
    }
  return tie_averaged_direction(dirs, len, best, d_max, tolerance, cone_deg);
}

FeretResult feret_exact(const ConvexHull& hull, const FeretExactOptions& opt) {
  FeretResult r;
  if (hull.vertices.empty()) return r;
  r.d_max = hull_diameter(hull, &r.dir_max);
  if (hull.dimension < 3) return r;
  r.dir_max = diameter_direction(hull, r.d_max, r.dir_max, opt.tie_tolerance, opt.tie_cone_deg);
  r.d_min = min_width_perpendicular(hull, r.dir_max, &r.dir_min);
  r.d_min_any = min_width(hull, &r.dir_min_any);
  return r;
}

}  // namespace tg::measure

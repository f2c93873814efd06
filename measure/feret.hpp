// Feret (caliper) sizing of a particle from the convex hull of its boundary.
//
// Caliper width along a unit direction u: W(u) = max_p u.p - min_p u.p over
// the hull vertices p (a convex body's width is its hull's width).
//
// Sampled mode (the reference study's method, default N = 60): N quasi-uniform
// directions on the half-sphere (Fibonacci / golden-spiral lattice, Gonzalez
// 2010, doi:10.1007/s11004-009-9257-x; +-u give the same width, so a
// half-sphere suffices). Dmax = max W; Dmin = min W over M directions on the
// great half-circle perpendicular to the Dmax direction, M = ceil(sqrt(pi N /
// 2)) so that the circle is sampled at the same angular step as the sphere
// (N points on a half-sphere of area 2 pi are ~sqrt(2 pi / N) rad apart: 18
// deg for N = 60, M = 10); Dmin_any = min W over the N directions.
// Cost O((N + M) h) for h hull vertices.
//
// Exact mode (the reference for the sampled mode's bias):
//  * Dmax = hull diameter, max |p - q| over vertex pairs, O(h^2).
//  * Dmin = minimum width of the hull's projection onto the plane
//    perpendicular to Dmax: 2-D hull (monotone chain) then, for each of its
//    edges, the farthest vertex (a minimum-width direction of a convex
//    polygon is always an edge normal; Toussaint 1983 rotating calipers).
//    The Dmax *direction* is ill-conditioned on flat, disc-like particles:
//    tilting a half-sphere's diameter by e out of its flat face shortens it by
//    only ~Dmax e^2 / 8, so a tenth of a voxel of digitisation noise tilts it
//    by ~10 deg, and the width perpendicular to it then reads R (1 + sin e)
//    instead of R. So every vertex pair within tie_tolerance (~half a voxel)
//    of Dmax is a candidate Dmax direction (up to 32, >= 3 deg apart) and
//    Dmin is the smallest perpendicular width over the candidates. With
//    tie_tolerance = 0 this is the textbook definition.
//  * Dmin_any = the 3-D minimum width: attained at a face-vertex or an
//    edge-edge antipodal pair (Houle & Toussaint 1988, IEEE PAMI 10(5):761,
//    doi:10.1109/34.6790). Faces: O(F h). Edge pairs: two edges are antipodal
//    when the arc of one on the Gauss sphere (between its two face normals)
//    crosses the reflected arc of the other; arcs are sorted by the z of their
//    mid-normal so that only arcs within reach are tested (O(E^2) worst case,
//    far less on the fine hulls of voxel particles).
//
// Point convention (why the hull is not built on voxel centres or corners):
// the hull of voxel *centres* under-reads calipers (along a lattice axis the
// outermost centre sits on average half a voxel inside the true surface on
// each side; along generic directions the gap is small), while the hull of
// voxel *corners* adds |u_x| hx + |u_y| hy + |u_z| hz, up to 1.7 voxels, to
// every caliper (FR of a 20-voxel sphere +0.1). tomograin builds the hull on
// one point per *exposed voxel face*: the centre of a boundary voxel pushed
// out by lambda/2 voxel towards that face (lambda = face_offset, default
// 0.5: a quarter voxel). That hull is the Minkowski sum of the centres' hull and an
// octahedron of half-diagonals lambda h_i / 2, so every caliper becomes
//     W(u) = W_centres(u) + lambda max_i |u_i| h_i
// (tested), adding the most along the lattice axes, where the centres lose
// the most. lambda = 0.5 is measured, not derived (measure_feret_bench
// convention; exact mode, mean over 6 random placements, worst in ()):
//                        r=10          r=20          r=30 voxels
//   sphere mean caliper  +0.6 % (0.7)  +0.5 % (0.5)  +0.4 % (0.4)  (vs 2r)
//   sphere Dmed          +0.8 % (1.0)  +0.2 % (0.2)  -0.1 % (0.4)
//   sphere FR - 1        -0.036 (.039) -0.014 (.015) -0.005 (.013)
//   sphere AR - 1        +0.051 (.052) +0.024 (.024) +0.014 (.018)
//   half-sphere FR - 0.5 +0.024 (.038) +0.020 (.024) +0.014 (.021)
// Larger lambda helps spheres' FR and hurts flat faces (lambda = 0.8:
// half-sphere FR +0.036 at r = 20, sphere FR +0.004); smaller does the
// reverse (0.2: sphere FR -0.031, half-sphere +0.005). The sphere's AR
// excess, ~1.2 voxels / (2r) whatever lambda, is the lattice's own
// quantisation of the narrowest direction. Each voxel contributes points on
// both sides of its centre, so the hull is always 3-D, even for one voxel.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "measure/hull.hpp"

namespace tg::measure {

// A boundary voxel of a particle: its (k, j, i) and which of its six faces
// touch another label, void or the volume's edge (bit 0: -z, 1: +z, 2: -y,
// 3: +y, 4: -x, 5: +x).
struct SurfaceVoxel {
  int32_t k = 0, j = 0, i = 0;
  uint8_t exposed = 0;
};

// Hull input points of one particle, in metres, (z, y, x) order, relative to
// `anchor` (a voxel index near the particle, so the coordinates stay small):
// one point per exposed face, centre + lambda/2 * h along the face normal.
std::vector<Vec3> caliper_points(std::span<const SurfaceVoxel> surface, const std::array<double, 3>& voxel_size_m,
                                 const std::array<int64_t, 3>& anchor, double face_offset = 0.5);

// Quasi-uniform unit directions on the upper half-sphere (z >= 0 in the
// vector's own 3rd component), golden-spiral construction, deterministic.
std::vector<Vec3> half_sphere_directions(int n);

// Caliper width of the hull along unit direction u.
double caliper_width(const ConvexHull& hull, const Vec3& u);

struct FeretResult {
  double d_max = 0;      // largest caliper
  double d_min = 0;      // smallest caliper perpendicular to the d_max direction
  double d_min_any = 0;  // smallest caliper in any direction
  Vec3 dir_max = Vec3::UnitX(), dir_min = Vec3::UnitY(), dir_min_any = Vec3::UnitZ();
};

// Sampled mode on the given directions (see half_sphere_directions). n_perp:
// directions on the half-circle perpendicular to Dmax, 0 = ceil(sqrt(pi N/2)).
FeretResult feret_sampled(const ConvexHull& hull, std::span<const Vec3> directions, int n_perp = 0);

struct FeretExactOptions {
  // Directions whose caliper is within tie_tolerance of Dmax count as Dmax
  // directions (same length unit as the hull; the caller passes ~half a
  // voxel). Zero = the single diameter pair only.
  double tie_tolerance = 0;
  int max_candidates = 32;          // at most this many candidate Dmax directions...
  double min_separation_deg = 3.0;  // ...at least this far apart
};

// Exact mode (see the header comment). Hull must be 3-D; a flat hull gets
// Dmin = Dmin_any = 0.
FeretResult feret_exact(const ConvexHull& hull, const FeretExactOptions& opt = {});

// Directions of vertex pairs at least d_max - tolerance apart, longest first,
// thinned to max_count directions at least min_separation_deg apart.
std::vector<Vec3> diameter_candidates(const ConvexHull& hull, double d_max, double tolerance, int max_count,
                                      double min_separation_deg);

// The pieces of the exact mode, exposed for tests and the benchmark.
double hull_diameter(const ConvexHull& hull, Vec3* direction = nullptr);
double min_width(const ConvexHull& hull, Vec3* direction = nullptr);
double min_width_perpendicular(const ConvexHull& hull, const Vec3& axis, Vec3* direction = nullptr);

}  // namespace tg::measure

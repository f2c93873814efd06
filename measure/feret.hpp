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
// Cost O((N + M) h) for h hull vertices. The same tie rule as the exact mode
// (below) is available (tie_tolerance); the particle table uses it.
//
// Exact mode (the reference for the sampled mode's bias):
//  * Dmax = hull diameter, max |p - q| over vertex pairs, O(h^2).
//  * Dmin = minimum width of the hull's projection onto the plane
//    perpendicular to Dmax: 2-D hull (monotone chain) then, for each of its
//    edges, the farthest vertex (a minimum-width direction of a convex
//    polygon is always an edge normal; Toussaint 1983 rotating calipers).
//    The Dmax *direction* is ill-conditioned: on a flat, disc-like particle
//    tilting a half-sphere's diameter by e out of its flat face shortens it
//    by only ~Dmax e^2 / 8, so a tenth of a voxel of digitisation noise tilts
//    it by ~10 deg and the perpendicular width reads R (1 + sin e), not R; on
//    a box, the rounded digitised corners tilt the diagonal and the width
//    perpendicular to it moves fast with the tilt. Taking the smallest
//    perpendicular width over all near-tie directions fixes the first and
//    ruins the second (box FR -0.15 to -0.27), so the tie rule *fits*
//    instead. Near ties are the vertex pairs within tie_tolerance (~half a
//    voxel) of Dmax. If their directions spread over a plane (orientation
//    tensor eigenvalues l1 >= l2 > 0.1, l3 < 0.1 l2: a ring of equal
//    diameters, as on a disc or a half-sphere), the Dmax direction is the
//    diameter projected into that plane; otherwise (a cluster: a box
//    diagonal, a needle) it is the mean of the near-tie directions within
//    20 deg of the diameter. Both cancel tilt noise instead of exploiting
//    it. Dmax itself stays the diameter's length.
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
// 0.3). That hull is the Minkowski sum of the centres' hull and an
// octahedron of half-diagonals lambda h_i / 2, so every caliper becomes
//     W(u) = W_centres(u) + lambda max_i |u_i| h_i
// (tested), adding the most along the lattice axes, where the centres lose
// the most. lambda = 0.3 is measured, not derived (measure_feret_bench
// convention; exact mode with the tie rule, mean over 6 random placements,
// worst in ()):
//                        r=10           r=20           r=30 voxels
//   sphere mean caliper  -0.3 % (0.4)   +0.05 % (0.1)  +0.1 % (0.1)  (vs 2r)
//   sphere Dmed          +1.0 % (1.9)   +0.3 % (1.5)   -0.1 % (0.3)
//   sphere FR - 1        -0.030 (.046)  -0.012 (.034)  -0.003 (.010)
//   sphere AR - 1        +0.033 (.040)  +0.015 (.026)  +0.008 (.012)
//   half-sphere FR - 0.5 +0.013 (.046)  +0.013 (.018)  +0.012 (.019)
// Larger lambda helps spheres' FR and hurts flat faces (lambda = 0.5:
// half-sphere FR +0.027 at r = 20, sphere +0.004); the sphere's AR excess,
// ~0.5 voxel / (2r), is the lattice's own quantisation. Each voxel
// contributes points on both sides of its centre, so the hull is always
// 3-D, even for a single voxel. Boxes remain hard: the width perpendicular
// to a box's diagonal moves fast when the digitised corners tilt the
// diagonal (FR -0.12 on average, -0.18 worst, for 1.6:1:0.6 boxes of long
// edge 29 voxels; 1:0.6:0.35 ellipsoids: -0.004, worst 0.013).
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
// one point per exposed face, centre + lambda/2 * h along the face normal,
// keeping only points that end their grid line (along x, y and z) among
// points of the same face kind: the others lie inside the hull. Each point
// is moved by a deterministic pseudo-random offset below 1e-7 voxel: lattice
// points are massively coplanar, which sent most of CGAL's hull predicates
// to exact GMP arithmetic (perf: malloc + mpq at the top); breaking those
// exact ties makes the hull ~3x faster and moves calipers by < 2e-7 voxel.
std::vector<Vec3> caliper_points(std::span<const SurfaceVoxel> surface, const std::array<double, 3>& voxel_size_m,
                                 const std::array<int64_t, 3>& anchor, double face_offset = 0.3);

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

struct FeretSampledOptions {
  int n_perp = 0;  // directions on the perpendicular half-circle; 0 = ceil(sqrt(pi N / 2))
  // The tie rule (see the header): 0 = the study's literal definition, the
  // perpendicular circle of the single widest direction; > 0 = of the
  // direction fitted to the sampled directions within tie_tolerance of Dmax.
  double tie_tolerance = 0;
  double tie_cone_deg = 20;
};

// Sampled mode on the given directions (see half_sphere_directions).
FeretResult feret_sampled(const ConvexHull& hull, std::span<const Vec3> directions,
                          const FeretSampledOptions& opt = {});

struct FeretExactOptions {
  // Vertex pairs within tie_tolerance of the diameter (same length unit as
  // the hull; the particle table passes half a voxel) are fitted into the
  // Dmax direction (header; clusters use tie_cone_deg). 0 = the diameter pair.
  double tie_tolerance = 0;
  double tie_cone_deg = 20;
};

// Exact mode (see the header comment). Hull must be 3-D; a flat hull gets
// Dmin = Dmin_any = 0.
FeretResult feret_exact(const ConvexHull& hull, const FeretExactOptions& opt = {});

// The Dmax direction under the tie rule (header) from the vertex pairs at
// least d_max - tolerance long; `best` is the diameter's own direction.
Vec3 diameter_direction(const ConvexHull& hull, double d_max, const Vec3& best, double tolerance, double cone_deg);

// The pieces of the exact mode, exposed for tests and the benchmark.
double hull_diameter(const ConvexHull& hull, Vec3* direction = nullptr);
double min_width(const ConvexHull& hull, Vec3* direction = nullptr);
double min_width_perpendicular(const ConvexHull& hull, const Vec3& axis, Vec3* direction = nullptr);

}  // namespace tg::measure

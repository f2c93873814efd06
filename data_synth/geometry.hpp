// Geometry of a synthetic specimen: every particle is a union of convex
// "pieces" (a sphere intersected with half-spaces) minus void spheres (pores).
//
//   grain    one sphere, no planes                        (intact granule)
//   half     sphere ∩ {n·(p−c) ≥ g/2}: a spherical cap      (axial split, gap g)
//   multi    sphere ∩ 2–3 half-spaces: a wedge             (multi-fragmentation)
//   chip     thin cap sphere ∩ {n·(p−c) ≥ R−t}              (surface chip)
//   chipped  the rest of a chipped grain (a cap of height > R)
//   cluster  union of several spheres, one id               (DEM bonded fragment)
//
// Coordinates are in VOXEL units, ordered (z, y, x), with the project-wide
// convention: voxel (k, j, i) covers [k, k+1) × [j, j+1) × [i, i+1), its
// centre is (k+0.5, j+0.5, i+0.5). A sphere at (10, 10, 10) of radius 3 is
// centred on the corner shared by 8 voxels.
//
// Usage (the renderer is in data_synth/render.hpp):
//   std::vector<tg::synth::Particle> ps{tg::synth::make_grain(1, {20.3, 20, 20.7}, 7.5)};
//   auto r = tg::synth::render(ps, tg::Shape{40, 40, 40});   // r.solid (f32), r.labels (u32)
//   auto t = tg::synth::particle_truth(ps[0]);                // exact volume, centroid, Feret
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/sphere_table.hpp"
#include "core/volume.hpp"
#include "data_synth/rng.hpp"

namespace tg::synth {

using Vec3 = std::array<double, 3>;  // (z, y, x), voxel units

// Vector algebra on Vec3, one set for data_synth and the code that renders with it (compare/voxelise).
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
// The unit vector along v; +z for the zero vector (a degenerate direction still gives a valid plane).
inline Vec3 unit(const Vec3& v) {
  const double l = std::sqrt(dot(v, v));
  return l > 0 ? Vec3{v[0] / l, v[1] / l, v[2] / l} : Vec3{0, 0, 1};
}

struct Sphere {
  Vec3 c{0, 0, 0};
  double r = 0;
};

// Keeps the points p with dot(n, p) <= d; n is a unit vector (z, y, x).
struct HalfSpace {
  Vec3 n{0, 0, 1};
  double d = 0;
};

// Keeps n·(p − c) >= offset, as a HalfSpace (−n)·p <= −offset − n·c.
inline HalfSpace keep_above(const Vec3& n, const Vec3& c, double offset) {
  return HalfSpace{{-n[0], -n[1], -n[2]}, -offset - dot(n, c)};
}

// Random unit vector from draws n..n+5 of stream (seed, key) (data_synth/rng.hpp).
inline Vec3 random_direction(uint64_t seed, uint64_t key, uint64_t n) {
  return unit({normal01(seed, key, n), normal01(seed, key, n + 2), normal01(seed, key, n + 4)});
}

// A convex piece: sphere ∩ all planes.
struct Piece {
  Sphere sphere;
  std::vector<HalfSpace> planes;
};

enum class Kind : int { grain = 0, half = 1, multi = 2, chip = 3, chipped = 4, cluster = 5 };
const char* kind_name(Kind k);  // "grain", "half", ...
Kind kind_from_name(const std::string& name);  // throws InputError on an unknown name

struct Particle {
  uint32_t id = 0;      // label value, > 0
  Kind kind = Kind::grain;
  uint32_t parent = 0;  // id of the grain it came from (= id for intact grains, 0 if none)
  std::vector<Piece> pieces;  // union
  std::vector<Sphere> pores;  // void spheres, each entirely inside one piece
};

// Intact spherical grain (parent = id).
Particle make_grain(uint32_t id, Vec3 c, double r);
// Spherical cap of `s` on the side n·(p−c) >= offset (n unit): half (offset = gap/2),
// chip (offset = R − thickness) or chipped body (offset < 0). Kind is given.
Particle make_cap(uint32_t id, Kind kind, uint32_t parent, const Sphere& s, Vec3 n, double offset);
// Union of spheres, one id.
Particle make_cluster(uint32_t id, uint32_t parent, std::vector<Sphere> spheres);

// A DEM sphere table (core/sphere_table.hpp, metres) as particles in the voxel
// coordinates of `geometry` (isotropic voxel size required): the spheres that
// share a particle id become one particle — a lone sphere a `grain`, several a
// `cluster` — with ids 1..n in the order the particle ids first appear. The
// one mapping used by `synth --particles`, `voxelise` and `compare`, so the
// three see the same particles. particle_of_label (optional) receives the
// input id of label l at index l (index 0 unused: -1).
std::vector<Particle> particles_from_spheres(const SphereTable& s, const Geometry& geometry,
                                             std::vector<int64_t>* particle_of_label = nullptr);

// Axis-aligned bounding box [lo, hi] of a particle (voxel units).
void bounding_box(const Particle& p, Vec3& lo, Vec3& hi);

// Exact ground truth of one particle. Volume and centroid are analytic for
// grains and caps (half, chip, chipped; pores subtracted exactly); for multi
// and clusters the volume comes from the partial-volume rules on 16³ cells of
// the bounding box with 5 subdivision levels (tested: quarter sphere and a
// two-sphere lens within 1e-6 relative), the centroid from a chord rule
// (tested within 1e-4 voxel).
// Feret sizes follow measure/: Dmax = largest caliper, Dmin = smallest caliper
// perpendicular to Dmax, Dmed = 6V/(π Dmax Dmin), FR = Dmin/Dmed,
// AR = Dmax/Dmin. They are exact for grains (Dmax = Dmin = Dmed = 2R) and caps of
// height h: h <= R: Dmax = 2√(h(2R−h)), Dmin = h; h > R: Dmax = 2R, Dmin = h.
// For multi and cluster they are NaN (no closed form). Pores are subtracted
// from `volume` but not from the V in Dmed (the pipeline fills intra-granular
// pores before measuring; a porous sphere keeps FR = AR = 1).
struct Truth {
  double volume = 0;         // voxel^3
  Vec3 centroid{0, 0, 0};    // voxel units
  double radius = 0;         // radius of the parent sphere (largest sphere for clusters)
  double dmax = 0, dmin = 0, dmed = 0, fr = 0, ar = 0;
};
Truth particle_truth(const Particle& p);

// Spherical cap of height h (0 <= h <= 2R): volume π h² (3R − h)/3 and distance
// of its centroid from the sphere centre 3(2R − h)² / (4(3R − h)).
double cap_volume(double R, double h);
double cap_centroid_offset(double R, double h);

}  // namespace tg::synth

// Exact Euclidean distance transform of a binary volume, anisotropic voxels.
//
// For every solid (nonzero) voxel: the distance from its centre to the
// centre of the nearest void (zero) voxel, with voxel edge lengths
// spacing = (z, y, x); void voxels get 0. Voxels outside the volume do not
// count as void (as scipy.ndimage.distance_transform_edt): a grain cut by
// the border keeps its full depth there. A volume without any void voxel
// gets +infinity everywhere.
//
// Method: Felzenszwalb and Huttenlocher, "Distance transforms of sampled
// functions", Theory of Computing 8:415-428 (2012),
// doi:10.4086/toc.2012.v008a019. The squared distance is separable,
//   D(k,j,i) = min over (k',j',i') of wz^2(k-k')^2 + wy^2(j-j')^2 + wx^2(i-i')^2
// restricted to void voxels, so it is computed by three 1-D passes. Pass x
// is a two-sided sweep (distance to the nearest void voxel of the row).
// Passes y and z compute, on each line, d(p) = min over q of
// (w (p - q))^2 + f(q) (f from the passes before), in one of two ways,
// chosen per block of 16 neighbouring lines:
// - Windows (most blocks of a granular scan): the nearest q lies within
//   sqrt(f(p)) / w of p, since d(p) <= f(p); the minimum is taken directly
//   over that window, 16 lines at once in SIMD, in float (exact for integer
//   squared distances below 2^24, i.e. isotropic voxels in volumes up to
//   ~2300 per side; otherwise within 1-2 float roundings).
// - Lower envelope of the parabolas rooted at every site q with finite f
//   (the paper's algorithm, O(n)), where windows would be wide (rows
//   without void, large grains): a stack of parabolas and the abscissae
//   where each takes over. Deviations from the paper: spacing w on each
//   axis, voxel units along the line (g(q) = f(q) / w^2 + q^2, the
//   intersection of v < q is (g(q) - g(v)) / (2 (q - v))), intersections
//   compared by cross-multiplication (no division), sites with f = +inf
//   kept finite but never nearest (no inf - inf), lines cut at zeros;
//   built in double, stored as float.
//
// Parallelism: OpenMP over slices (passes x, y) and over y (pass z),
// schedule(static); a line's result does not depend on which thread
// computes it. Passes y and z copy the rows they need whole into a
// per-thread slab (sequential memory access) and solve 16 columns at a time.
// Pass x runs slice by slice into the slab pass y reads, and
// distance_transform takes the square root in the last pass.
//
// Cost: O(N) time for the envelopes, O(N r) for the windows (r: the local
// depth in voxels, bounded by the choice between the two); 3 passes
// (measured at 256^3 on one core: 25 -> ~115 Mvox/s, see
// bench/segmentation/RESULTS.md); no memory beyond the float output
// (4 B/voxel) and per-thread slabs (8 B x the larger of ny nx, nz nx).
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include "core/volume.hpp"

namespace tg {

struct EdtOptions {
  // Voxel edge lengths (z, y, x), any unit; distances come out in that unit.
  // segment() passes the voxel size divided by its smallest component, so
  // distances are in units of the finest voxel edge.
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
  // Mask values >= solid_from are solid, the rest void (segment() passes 2
  // on its graded mask: the distance to the nearest void or dim voxel).
  uint8_t solid_from = 1;
};

// Squared distances into `out` (reallocated if its shape differs; geometry
// copied from `solid`). Throws UsageError for a non-positive spacing.
void squared_distance_transform(const Volume<uint8_t>& solid, Volume<float>& out, const EdtOptions& opt = {});

// Distances (square root of the above, in place).
void distance_transform(const Volume<uint8_t>& solid, Volume<float>& out, const EdtOptions& opt = {});

// The distance map in 16-bit fixed point, for the steps after the EDT
// (markers, flood levels), which only compare distances: value =
// round(d * per_unit), at least 1 where d > 0 (so the solid is exactly
// where value > 0), 0 on the void. per_unit = fixed_point_units(dmax):
// 256, steps of 1/256 voxel (1/512 at most off) for grains up to 255
// voxels deep, far below the digital map's own staircase ripples (~0.5)
// and the marker depth h (>= 0.7). Why: a float map beside the u32
// markers made 8 B/voxel the segmentation's peak; at 2 B the peak is
// 6 B/voxel (issue #23: a 1220^3 scan within 7 B/voxel).
struct FixedDistance {
  Volume<uint16_t> map;
  double per_unit = 1.0;  // fixed-point units per distance unit
  float dmax = 0;         // the float map's deepest value (the flood's quantisation is decided on it)
};

// The map's deepest value; UsageError (naming `who`) when a value is NaN,
// infinite or negative.
float deepest_distance(const Volume<float>& dist, const std::string& who);

// 256 while dmax <= 255, else the largest power of two that keeps dmax
// within 16 bits. A scan segmented slab by slab gives each slab the whole
// scan's (a slab's own deepest voxel may be shallower).
double fixed_point_units(float dmax);

// Converts a distance map (finite, >= 0) over its own storage (taken; the
// spent 2 B/voxel are given back), at per_unit units per distance unit
// (0: fixed_point_units of its own deepest value; values past 65535
// clamp). UsageError on NaN, inf or < 0.
FixedDistance to_fixed_point(Volume<float>&& dist, double per_unit = 0);

namespace detail {
// One parabola of a lower envelope, in voxel units along its line: root v,
// g = f(v) / w^2 + v^2, f = f(v) (kept for the output), and the abscissa
// zn / zd (zd >= 0) where it takes over from the parabola below it on the
// stack; -1 / 0 stands for -infinity and 1 / 0 for +infinity.
struct EnvelopeSite {
  double v, g, f, zn, zd;
};

// Lower envelope of parabolas on one line of n samples with spacing w, read
// from f and written to d at `stride` floats between samples (d may be f):
// d[p] = min_q (w (p - q))^2 + f[q] over q with finite f (all +inf if none).
// Scratch: n + 1 sites.
void edt_line(const float* f, float* d, int64_t n, int64_t stride, double w, EnvelopeSite* sites);

// Passes y and z work on blocks of kEdtBlock lines stored row by row:
// sample p of line b at [p * stride + b], stride >= kEdtBlock.
constexpr int64_t kEdtBlock = 16;

// The same minimum as edt_line on a block of lines, taken directly over the
// window |q - p| <= r_p of each row (out may not alias in); computed in
// float. Returns false, writing nothing to out, when the windows would cost
// more than the envelopes (see the .cpp). Scratch: n radii, n costs.
bool edt_block_window(const float* in, float* out, int64_t n, int64_t stride, double w, int64_t* radius, float* cost);
}  // namespace detail

}  // namespace tg

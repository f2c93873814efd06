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
// Passes y and z compute, on each line, the lower envelope of the parabolas
// p -> (w (p - q))^2 + f(q) rooted at every site q with finite f, in O(n):
// a stack of parabolas and the abscissae z[] where each takes over. Sites
// with f = +inf are skipped (the paper's algorithm would form inf - inf).
// Deviations from the paper: spacing w on each axis (the intersection is
// s = ((f(q) + (w q)^2) - (f(v) + (w v)^2)) / (2 w (q - v)) in physical
// units), and the envelope is built in double then stored as float.
//
// Parallelism: OpenMP over independent lines, schedule(static); a line's
// result does not depend on which thread computes it. Passes y and z gather
// 16 neighbouring columns at once so each memory read uses a full cache
// line instead of one float of it.
//
// Cost: O(N) time, 3 passes; no memory beyond the float output (4 B/voxel)
// and per-thread line scratch.
#pragma once
#include <array>
#include <cstdint>

#include "core/volume.hpp"

namespace tg {

struct EdtOptions {
  // Voxel edge lengths (z, y, x), any unit; distances come out in that unit.
  // segment() passes the voxel size divided by its smallest component, so
  // distances are in units of the finest voxel edge.
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
};

// Squared distances into `out` (reallocated if its shape differs; geometry
// copied from `solid`). Throws UsageError for a non-positive spacing.
void squared_distance_transform(const Volume<uint8_t>& solid, Volume<float>& out, const EdtOptions& opt = {});

// Distances (square root of the above, in place).
void distance_transform(const Volume<uint8_t>& solid, Volume<float>& out, const EdtOptions& opt = {});

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
}  // namespace detail

}  // namespace tg

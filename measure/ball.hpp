// The voxels of a label volume inside a ball: the neighbourhood that the
// contact normals (measure/contacts.cpp) and the surface normals
// (measure/surface.cpp) are estimated from.
//
// Ball of radius rho (metres) around m (voxel index space: voxel centres at
// integer coordinates), anisotropic voxel edges from the volume's geometry,
// clipped to the volume. f(k, j, i, dz, dy, dx, label) is called for each
// voxel inside, in index order, with (dz, dy, dx) its offset from m in metres.
// Cost O(rho^3 / voxel volume); no allocation.
// A slab of a larger volume (measure_chunked.hpp): the view holds slices
// k_offset .. k_offset + its nz - 1 of a volume of nz_total slices, and m,
// the clipping and the k given to f are the whole volume's; the slab must
// hold every slice the ball reaches (UsageError otherwise).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <string>

#include "core/errors.hpp"
#include "core/volume.hpp"

namespace tg::measure {

template <class F>
void for_each_voxel_in_ball(const VolumeView<const uint32_t>& v, const double m[3], double rho, F&& f,
                            int64_t k_offset = 0, int64_t nz_total = -1) {
  const Shape s = v.shape();
  const auto& h = v.geometry().voxel_size_m;
  const int64_t n[3] = {nz_total < 0 ? s.nz : nz_total, s.ny, s.nx};
  int64_t lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    const double r = rho / h[d];
    lo[d] = std::max<int64_t>(0, static_cast<int64_t>(std::ceil(m[d] - r)));
    hi[d] = std::min<int64_t>(n[d] - 1, static_cast<int64_t>(std::floor(m[d] + r)));
  }
  if (lo[0] <= hi[0] && (lo[0] < k_offset || hi[0] >= k_offset + s.nz))
    throw UsageError("ball of slices " + std::to_string(lo[0]) + ".." + std::to_string(hi[0]) +
                     " outside the slab of slices " + std::to_string(k_offset) + ".." +
                     std::to_string(k_offset + s.nz - 1));
  const double rho2 = rho * rho;
  for (int64_t k = lo[0]; k <= hi[0]; ++k) {
    const double dz = (static_cast<double>(k) - m[0]) * h[0];
    for (int64_t j = lo[1]; j <= hi[1]; ++j) {
      const double dy = (static_cast<double>(j) - m[1]) * h[1];
      const double rem = rho2 - dz * dz - dy * dy;
      if (rem < 0) continue;
      const double r = std::sqrt(rem) / h[2];
      const int64_t i0 = std::max(lo[2], static_cast<int64_t>(std::ceil(m[2] - r)));
      const int64_t i1 = std::min(hi[2], static_cast<int64_t>(std::floor(m[2] + r)));
      const uint32_t* row = v.row(k - k_offset, j).data();
      for (int64_t i = i0; i <= i1; ++i) f(k, j, i, dz, dy, (static_cast<double>(i) - m[2]) * h[2], row[i]);
    }
  }
}

}  // namespace tg::measure

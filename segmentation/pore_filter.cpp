#include "segmentation/pore_filter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "core/errors.hpp"
#include "segmentation/connected_components.hpp"

namespace tg {

PoreFilterOptions PoreFilterOptions::from_grain_radius(double r) {
  if (!(r > 0)) throw UsageError("pore filter: the expected grain radius must be positive (voxels)");
  PoreFilterOptions o;
  o.max_volume_vox = std::max<int64_t>(1, std::llround(0.02 * 4.0 / 3.0 * std::numbers::pi * r * r * r));
  o.min_sphericity = 0.5;
  return o;
}

std::string PoreFilterOptions::describe() const {
  std::ostringstream s;
  s << "fill enclosed voids with volume <= " << max_volume_vox << " voxels and sphericity >= " << min_sphericity
    << " (36 pi V^2/A^3, A = 2/3 of the voxel faces)";
  return s.str();
}

double voxel_sphericity(int64_t volume_vox, int64_t faces) {
  if (volume_vox <= 0 || faces <= 0) return 0.0;
  const double v = double(volume_vox), a = 2.0 / 3.0 * double(faces);
  return std::min(1.0, 36.0 * std::numbers::pi * v * v / (a * a * a));
}

PoreFilterResult fill_pores(Volume<uint8_t>& solid, Volume<uint32_t>& scratch, const PoreFilterOptions& opt) {
  if (opt.max_volume_vox < 0 || !(opt.min_sphericity >= 0 && opt.min_sphericity <= 1))
    throw UsageError("pore filter: max volume must be >= 0 and min sphericity in [0, 1]");
  const auto cc = connected_components(solid, scratch, {6, Phase::zero, 1});
  PoreFilterResult res;
  res.void_components = cc.count;
  if (cc.count == 0) return res;

  // Per component: touches the border? faces shared with solid.
  const Shape s = solid.shape();
  const uint8_t* m = solid.data();
  const uint32_t* L = scratch.data();
  std::vector<uint8_t> border(size_t(cc.count) + 1, 0);
  std::vector<int64_t> faces(size_t(cc.count) + 1, 0);
  const int64_t sy = s.nx, sz = s.slice_voxels();
  // Components that reach a face of the volume are not enclosed: found on
  // the six faces alone. The rest of the volume then counts solid faces
  // around the other components only, skipping the inter-granular void
  // (nearly all void voxels), in parallel (integer sums: any order).
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j) {
      const bool whole = k == 0 || k + 1 == s.nz || j == 0 || j + 1 == s.ny;
      for (int64_t i = 0; i < s.nx; i += whole ? 1 : std::max<int64_t>(1, s.nx - 1))
        border[L[s.index(k, j, i)]] = 1;
    }
  border[0] = 1;  // solid
#pragma omp parallel if (int64_t(cc.count) <= s.voxels() / 16)  // per-thread tables: see connected_components
  {
    std::vector<int64_t> mine(faces.size(), 0);
#pragma omp for schedule(static)
    for (int64_t k = 1; k < s.nz - 1; ++k)
      for (int64_t j = 1; j < s.ny - 1; ++j)
        for (int64_t i = 1; i < s.nx - 1; ++i) {
          const int64_t idx = s.index(k, j, i);
          const uint32_t l = L[idx];
          if (border[l]) continue;
          mine[l] += (m[idx - 1] != 0) + (m[idx + 1] != 0) + (m[idx - sy] != 0) + (m[idx + sy] != 0) +
                     (m[idx - sz] != 0) + (m[idx + sz] != 0);
        }
#pragma omp critical
    for (size_t l = 0; l < faces.size(); ++l) faces[l] += mine[l];
  }
  std::vector<uint8_t> fill(size_t(cc.count) + 1, 0);
  for (uint32_t l = 1; l <= cc.count; ++l) {
    if (border[l]) continue;
    ++res.enclosed;
    const int64_t v = cc.sizes[l];
    if (v <= opt.max_volume_vox && voxel_sphericity(v, faces[l]) >= opt.min_sphericity) {
      fill[l] = 1;
      ++res.filled;
      res.filled_voxels += v;
    }
  }
  uint8_t* mw = solid.data();
  const int64_t n = solid.size();
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
    if (fill[L[i]]) mw[i] = 1;  // fill[0] = 0: solid voxels untouched
  return res;
}

}  // namespace tg

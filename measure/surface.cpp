#include "measure/surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/errors.hpp"
#include "measure/ball.hpp"

namespace tg::measure {

double surface_area(const VolumeView<const uint32_t>& v, uint32_t label, std::span<const SurfaceVoxel> surface,
                    const SurfaceOptions& opt) {
  if (!(opt.normal_radius_voxels >= 1 && opt.normal_radius_voxels <= 16))
    throw UsageError("surface: normal_radius_voxels must be in [1, 16], got " + std::to_string(opt.normal_radius_voxels));
  const auto& h = v.geometry().voxel_size_m;
  const double face[3] = {h[1] * h[2], h[0] * h[2], h[0] * h[1]};
  const double rho = opt.normal_radius_voxels * std::cbrt(h[0] * h[1] * h[2]);
  const double rho2 = rho * rho;
  double area = 0;
  for (const auto& sv : surface) {
    const int64_t p[3] = {sv.k, sv.j, sv.i};
    for (int f = 0; f < 6; ++f) {
      if (!(sv.exposed & (1u << f))) continue;
      const int ax = f / 2;
      const double sign = f % 2 ? 0.5 : -0.5;
      double m[3] = {static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])};
      m[ax] += sign;  // the face centre, voxel index space (centres at integers)
      // Weighted centroid of the particle's voxels, smooth weights
      // (1 - r^2/rho^2)^2: a hard ball's discrete shells made the estimate
      // jump with the radius (sphere area -2.4 % at 3.75 voxels, +1 % at 4).
      double sw = 0, cz = 0, cy = 0, cx = 0;
      for_each_voxel_in_ball(v, m, rho, [&](int64_t, int64_t, int64_t, double dz, double dy, double dx, uint32_t l) {
        if (l != label) return;
        const double q = 1.0 - (dz * dz + dy * dy + dx * dx) / rho2;
        const double wt = q * q;
        sw += wt; cz += wt * dz; cy += wt * dy; cx += wt * dx;
      });
      double w = 1.0;  // an empty ball cannot happen (the face's own voxel is inside it); keep the face
      if (sw > 0) {
        const double nz = -cz, ny = -cy, nx = -cx;  // from the centroid to the centre
        const double len = std::sqrt(nz * nz + ny * ny + nx * nx);
        const double comp = ax == 0 ? nz : ax == 1 ? ny : nx;
        if (len > 0) w = std::abs(comp) / len;
      }
      area += face[ax] * w;
    }
  }
  return area;
}

double wadell_sphericity(double volume_m3, double area_m2) {
  if (!(area_m2 > 0)) return std::numeric_limits<double>::quiet_NaN();
  return std::cbrt(std::numbers::pi) * std::pow(6.0 * volume_m3, 2.0 / 3.0) / area_m2;
}

}  // namespace tg::measure

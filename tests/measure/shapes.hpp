// Test fixtures: analytic shapes drawn into label volumes by voxel-centre
// inclusion (voxel (k, j, i) belongs to a shape when its centre
// (k+0.5, j+0.5, i+0.5) does), in voxel units, (z, y, x) order.
#pragma once
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "core/volume.hpp"

namespace tg::measure::test {

using V3 = Eigen::Vector3d;
using Inside = std::function<bool(const V3&)>;

inline Inside sphere(V3 c, double r) {
  return [=](const V3& p) { return (p - c).squaredNorm() <= r * r; };
}
// Half of a sphere: the side of the plane through c where (p - c).n >= 0.
inline Inside half_sphere(V3 c, double r, V3 n) {
  n.normalize();
  return [=](const V3& p) { return (p - c).squaredNorm() <= r * r && (p - c).dot(n) >= 0; };
}
// Box of full edge lengths e (along the columns of R), centred at c.
inline Inside box(V3 c, V3 e, Eigen::Matrix3d R) {
  return [=](const V3& p) {
    const V3 q = R.transpose() * (p - c);
    return std::abs(q[0]) <= e[0] / 2 && std::abs(q[1]) <= e[1] / 2 && std::abs(q[2]) <= e[2] / 2;
  };
}
// Ellipsoid of semi-axes s (along the columns of R), centred at c.
inline Inside ellipsoid(V3 c, V3 s, Eigen::Matrix3d R) {
  return [=](const V3& p) {
    const V3 q = R.transpose() * (p - c);
    return (q.array() / s.array()).square().sum() <= 1.0;
  };
}

// A uniformly random rotation (normalised Gaussian quaternion), seeded.
inline Eigen::Matrix3d random_rotation(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.toRotationMatrix();
}
// A random sub-voxel offset in [0, 1)^3, seeded.
inline V3 random_offset(unsigned seed) {
  std::mt19937 rng(seed * 7919u + 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  return V3(u(rng), u(rng), u(rng));
}

struct Drawn {
  uint32_t label;
  Inside inside;
};

// Draws shapes (later ones overwrite earlier ones) into a zero volume.
inline Volume<uint32_t> draw(Shape s, const std::vector<Drawn>& shapes, double voxel_m = 1e-5) {
  auto v = Volume<uint32_t>::filled(s, 0, Geometry::isotropic_m(voxel_m));
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        const V3 p(k + 0.5, j + 0.5, i + 0.5);
        for (const auto& d : shapes)
          if (d.inside(p)) v(k, j, i) = d.label;
      }
  return v;
}

// One shape in a volume just large enough (margin 2), centred near the
// middle with a sub-voxel offset.
inline Volume<uint32_t> draw_one(double half_extent, const std::function<Inside(V3)>& make, unsigned seed,
                                 double voxel_m = 1e-5) {
  const int64_t n = static_cast<int64_t>(std::ceil(2 * half_extent)) + 4;
  const V3 c = V3::Constant(n / 2.0) + random_offset(seed) - V3::Constant(0.5);
  return draw(Shape{n, n, n}, {{1, make(c)}}, voxel_m);
}

}  // namespace tg::measure::test

#include "dem/particles.hpp"

#include <numbers>

namespace tg::dem {

int64_t Particles::append_sphere(double px, double py, double pz, double radius, double density, int64_t grain_id,
                                 int32_t mat, uint32_t fl) {
  const int64_t i = size();
  resize(i + 1);  // every field, zero-initialised
  const auto k = static_cast<size_t>(i);
  x[k] = px;
  y[k] = py;
  z[k] = pz;
  r[k] = radius;
  m[k] = density * 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
  inertia[k] = 0.4 * m[k] * radius * radius;  // solid sphere: 2/5 m r^2
  particle[k] = grain_id;
  previous_particle[k] = grain_id;
  material[k] = mat;
  flags[k] = fl;
  return i;
}

}  // namespace tg::dem

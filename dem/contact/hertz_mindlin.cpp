#include "dem/contact/hertz_mindlin.hpp"

#include <string>

#include "core/errors.hpp"

namespace tg::dem {

namespace {
void check_material(const Material& m) {
  if (!(m.shear_modulus_Pa > 0) || !std::isfinite(m.shear_modulus_Pa))
    throw InputError("material: shear modulus must be positive and finite, got " + std::to_string(m.shear_modulus_Pa));
  if (!(m.poisson_ratio > -1 && m.poisson_ratio <= 0.5))
    throw InputError("material: Poisson's ratio must be in (-1, 0.5], got " + std::to_string(m.poisson_ratio));
  if (!(m.density_kg_m3 > 0) || !std::isfinite(m.density_kg_m3))
    throw InputError("material: density must be positive and finite, got " + std::to_string(m.density_kg_m3));
}
}  // namespace

HertzMindlin make_hertz_mindlin(const Material& a, const Material& b, double friction, double restitution) {
  check_material(a);
  check_material(b);
  if (!(friction >= 0) || !std::isfinite(friction))
    throw InputError("contact: friction coefficient must be >= 0, got " + std::to_string(friction));
  if (!(restitution > 0 && restitution <= 1))
    throw InputError("contact: restitution coefficient must be in (0, 1], got " + std::to_string(restitution));
  HertzMindlin law;
  const double ea = a.youngs_modulus(), eb = b.youngs_modulus();
  law.e_star = 1.0 / ((1 - a.poisson_ratio * a.poisson_ratio) / ea + (1 - b.poisson_ratio * b.poisson_ratio) / eb);
  law.g_star = 1.0 / ((2 - a.poisson_ratio) / a.shear_modulus_Pa + (2 - b.poisson_ratio) / b.shear_modulus_Pa);
  law.damp_t_over_n = std::sqrt(4 * law.g_star / law.e_star);
  law.friction = friction;
  if (restitution < 1) {
    const double le = std::log(restitution);
    law.damp_beta = -le / std::sqrt(le * le + std::numbers::pi * std::numbers::pi);
  }
  return law;
}

}  // namespace tg::dem

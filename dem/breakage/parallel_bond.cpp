#include "dem/breakage/parallel_bond.hpp"

#include <string>

#include "core/errors.hpp"

namespace tg::dem::breakage {

void validate(const ParallelBondParams& p) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw InputError(std::string("parallel bond: ") + name + " must be positive and finite, got " + std::to_string(v));
  };
  positive(p.radius_multiplier, "radius multiplier (lambda)");
  positive(p.youngs_modulus_Pa, "Young's modulus");
  positive(p.shear_modulus_Pa, "shear modulus");
  positive(p.tensile_strength_Pa, "normal (tensile) strength");
  positive(p.shear_strength_Pa, "shear strength");
  if (!(p.damping_ratio >= 0 && p.damping_ratio <= 1))
    throw InputError("parallel bond: damping ratio must be in [0, 1], got " + std::to_string(p.damping_ratio));
}

}  // namespace tg::dem::breakage

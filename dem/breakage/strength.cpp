#include "dem/breakage/strength.hpp"

#include <string>

#include "core/errors.hpp"

namespace tg::dem::breakage {

void validate(const StrengthParams& p) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw InputError(std::string("grain strength: ") + name + " must be positive and finite, got " + std::to_string(v));
  };
  positive(p.sigma_t0_Pa, "sigma_t0");
  positive(p.weibull_modulus, "Weibull modulus m");
  positive(p.d0_m, "reference size d0");
}

}  // namespace tg::dem::breakage

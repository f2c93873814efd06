#include "dem/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"

namespace tg::dem {

CriticalTimeStep critical_time_step(const Particles& p, const Material& mat, const TimeStepOptions& opt) {
  if (p.size() == 0) throw InputError("critical time step: no spheres");
  if (!(opt.reference_overlap > 0 && opt.reference_overlap < 1))
    throw InputError("critical time step: reference overlap must be in (0, 1)");
  double rmin = p.r[0], rmax = p.r[0], mmin = p.m[0];
  for (int64_t i = 1; i < p.size(); ++i) {
    rmin = std::min(rmin, p.r[i]);
    rmax = std::max(rmax, p.r[i]);
    mmin = std::min(mmin, p.m[i]);
  }
  const HertzMindlin law = make_hertz_mindlin(mat, mat, 0.0, 1.0);
  CriticalTimeStep c;
  c.m_min = mmin;
  c.k_max = law.normal_stiffness(opt.reference_overlap * rmax, rmax);
  c.dt_hertz = std::sqrt(mmin / c.k_max);
  const double nu = mat.poisson_ratio;
  c.dt_rayleigh = std::numbers::pi * rmin * std::sqrt(mat.density_kg_m3 / mat.shear_modulus_Pa) / (0.1631 * nu + 0.8766);
  c.dt_critical = std::min(c.dt_hertz, c.dt_rayleigh);
  return c;
}

}  // namespace tg::dem

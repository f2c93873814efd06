// Critical time step of an explicit DEM integration.
//
// Hertz contacts stiffen with overlap (kn = 2 E* sqrt(R* δ)), so a critical
// step needs a stated overlap. We take the stiffest contact the run should
// meet — a sphere of the largest radius against a flat wall (R* = r_max) at an
// overlap of `reference_overlap` × r_max — and the smallest mass:
//     dt_hertz = sqrt(m_min / k_max)
// (the study's t_crit = sqrt(m/k); a two-body Verlet oscillator is stable up
// to 2 sqrt(m*/k) = sqrt(2 m/k), so this keeps a margin for multi-contact
// modes). The Rayleigh-wave step used by many DEM codes (Li et al. 2005):
//     dt_rayleigh = π r_min sqrt(ρ/G) / (0.1631 ν + 0.8766)
// is reported too; dt_critical = min(dt_hertz, dt_rayleigh). A run uses
// safety × dt_critical when no explicit time step is given.
#pragma once
#include "dem/contact/hertz_mindlin.hpp"
#include "dem/particles.hpp"

namespace tg::dem {

struct TimeStepOptions {
  double reference_overlap = 0.05;  // δ / r_max at which kn is evaluated
};

struct CriticalTimeStep {
  double dt_hertz = 0, dt_rayleigh = 0, dt_critical = 0;
  double m_min = 0, k_max = 0;  // kg, N/m
};

// Throws InputError when there are no spheres.
CriticalTimeStep critical_time_step(const Particles& p, const Material& mat, const TimeStepOptions& opt);

}  // namespace tg::dem

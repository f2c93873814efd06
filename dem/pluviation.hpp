// Specimen preparation by pluviation, as in the reference study (§4.2):
// grains with a normal size distribution are generated at random, without
// overlap, in a tall cylinder (Ø15 mm × 30 mm) and settle under gravity
// until their kinetic energy is negligible.
//
// Sizes: diameters ~ N(μ = D50, σ) by number, truncated at ±3σ, with σ
// chosen so that the uniformity coefficient Cu = D60/D10 of the normal law is
// the requested one: D60 = μ + 0.2533σ, D10 = μ - 1.2816σ
//   ⇒ σ = (Cu - 1) μ / (0.2533 + 1.2816 Cu)   (D50 1.36 mm, Cu 1.07 → σ 0.0586 mm).
// Count: grains are drawn until their solid volume reaches
// (1 - n_target) π R² H_target, i.e. the grains that fill the study's
// specimen (H 12.25 mm) at the target porosity (44.5 %, mid of 44–45 %).
// The settled height then says how loose the deposit is. As in the study
// (§4.2: "the height of the sample was set to 12.25 mm"), a deposit that
// settles above the target height is then pressed down to it by the top
// platen (slowly, grains still frictionless), held until at rest, lifted
// off at the press speed until it carries nothing, and taken away; the oedometer measures strain from the top of the highest grain
// (as the LIGGGHTS peer does), so from 12.25 mm. Insertion: random sequential addition (uniform positions, rejected
// on overlap with a wall or an earlier grain), O(n²) checks (n ~ 10³).
#pragma once
#include <cstdint>

#include "dem/engine.hpp"

namespace tg::dem {

struct PluviationOptions {
  double d50_m = 1.36e-3;               // median diameter (study §2)
  double cu = 1.07;                     // uniformity coefficient D60/D10
  double cylinder_radius_m = 7.5e-3;    // Ø15 mm
  double generation_height_m = 30e-3;   // insertion cylinder height
  double target_height_m = 12.25e-3;    // specimen height in the study
  double target_porosity = 0.445;       // study: 44–45 %
  uint64_t seed = 1;
  double time_step_safety = 0.5;        // settle with this × critical step
  // Friction (grains and walls) while the grains fall and settle. Default 0:
  // frictionless deposition, the common DEM route to a dense specimen (the
  // grains cannot hold friction arches); for the study's 910 grains it gives
  // 12.42 mm / 45.2 % (μ 0.1: 12.77 mm / 46.7 %, the study's μ 0.5: 13.54 mm /
  // 49.7 %). The oedometer itself always uses [contact] friction.
  double deposition_friction = 0.0;
  // Press a deposit higher than target_height_m down to it (then release).
  // Off: the specimen is the free deposit (12.42 mm / 45.2 % for the study's
  // 910 grains); on: 12.25 mm / 44.5 %, the study's height and porosity.
  bool press_to_target_height = true;
  double press_speed_m_s = 0.02;        // top platen speed while pressing
  // Pressing stops early (the specimen stays higher than the target, which
  // is reported) if the platen stress exceeds this: a target the grains can
  // reach only by deforming is not forced.
  double press_max_stress_Pa = 10e3;
  double kinetic_energy_tol_J = 1e-9;   // settled when KE below (LIGGGHTS peer: 1e-9)...
  // ...at every check (1 ms apart) over this much simulated time. A single
  // check below the tolerance is not rest: a frictionless packing creeping
  // through a rearrangement (a grain sliding off an unstable perch while
  // another rises, KE ~5e-10 J and growing) passed it, and its pressed
  // specimens moved by up to 0.28 mm after "settling" (issue 25,
  // bench/dem/RESULTS.md). 0: one check, the former rule.
  double rest_window_s = 0.01;
  double max_time_s = 1.0;              // give up a settling phase after this (reported)
  int64_t max_insert_tries = 100000000; // RSA attempts before InputError
};

struct PluviationResult {
  Particles particles;
  double height_m = 0;    // top of the highest grain
  double porosity = 0;    // 1 - V_solid / (π R² height)
  double settle_time_s = 0;  // simulated time of the whole preparation
  double deposit_height_m = 0;     // free deposit, before any pressing
  double deposit_porosity = 0;
  bool pressed = false;            // the deposit was pressed towards target_height_m
  double held_height_m = 0;        // top of the highest grain at rest under the held platen, before release
  double press_stop_stress_Pa = 0; // platen stress when pressing stopped early (0: reached)
  double kinetic_energy_J = 0;
  bool settled = false;   // KE fell below the tolerance within max_time_s (every phase)
};

double sigma_from_cu(double d50, double cu);
// Random non-overlapping insertion only (no settling).
Particles insert_grains(const PluviationOptions& o, double density);
// Insertion + settling; `engine` gives material, contact and damping
// (its walls and time step are set here). Progress on a terminal.
PluviationResult pluviate(const PluviationOptions& o, EngineOptions engine);
// Height (top of the highest grain) and porosity of a packing in a cylinder.
void packing_height_porosity(const Particles& p, double cylinder_radius, double& height, double& porosity);

}  // namespace tg::dem

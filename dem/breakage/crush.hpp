// Single-particle crushing test (the "Brazilian" test of one grain between
// two platens, reference study §2 and §4.2): one sphere of diameter d rests
// on the fixed bottom platen (z = 0); the top platen starts touching it and
// moves down at constant speed. Gravity and the cylinder are off. With the
// breakage model on, the grain splits when F/d² first exceeds its Weibull
// strength (checked every check_interval steps), into two bonded fragments
// along the plane the rule predicts (two platen contacts only: σ2 = σ3,
// n_f ∥ σ1, so the fixed-axis rule gives the plane x = 0); loading continues
// and the fragments' bonds and elements break in turn.
//
// Before the split the force is the Hertz law of two sphere–platen contacts
// in series: F = 4/3 E* √r (u/2)^{3/2} for a platen travel u (quasi-static),
// so the split travel is predictable: u* = 2 [σs d² / (4/3 E* √r)]^{2/3}.
// Cost: 1 sphere, then 34 + … spheres; ~10⁵ steps for 40 % travel.
#pragma once
#include <cstdint>
#include <vector>

#include "dem/breakage/breakage.hpp"
#include "dem/engine.hpp"

namespace tg::dem::breakage {

struct CrushOptions {
  double diameter_m = 1.2e-3;        // grain diameter (zeolite granules: 1–2 mm)
  double platen_speed_m_s = 0.1;     // the study's loading speed
  double final_travel_fraction = 0.4;  // stop when the platen has moved this × d
  double time_step_s = 0;            // 0: 0.2 × √(m/k) of the grain at 5 % overlap
  int64_t history_every = 50;        // steps between history rows
  EngineOptions engine;              // material, friction, damping (walls are set here)
  BreakageOptions breakage;          // strength.d0_m: reference size (default 1 mm)
  bool breakage_on = true;
};

struct CrushRow {
  int64_t step = 0;
  double time_s = 0, travel_m = 0, force_N = 0;  // force on the top platen
  BreakageRecord record;
};

struct CrushResult {
  double strength_Pa = 0;       // drawn strength of the grain
  std::vector<CrushRow> history;
  std::vector<SplitEvent> splits;
  double time_step_initial_s = 0, time_step_final_s = 0;
  BreakageRecord final_record;
};

// Throws InputError on bad options (non-positive size or speed, …).
CrushResult run_crush(const CrushOptions& opt);

}  // namespace tg::dem::breakage

// What a calibration fits and how a run is scored (`tomograin dem calibrate`).
//
// The target file is TOML (every key optional except at least one target;
// unknown keys are errors), or a bare CSV curve (the stress–strain target
// alone, default weights and ranges):
//
//   [target]
//   stress_strain_csv = "curve.csv"  # columns strain and stress_Pa (or a run's
//                                    # history.csv: strain, top_stress_Pa); path
//                                    # relative to this file
//   yield_stress_Pa = 2.0e6          # the yield rule of dem/yield_stress.hpp
//   broken_strain = [0.044, 0.1548]  # broken fraction of the initial grains
//   broken_fraction = [0.05, 0.35]   # (grains_broken / grains) at these strains
//   broken_at_stress_Pa = [2e6, 4e6] # when the top stress first reaches these:
//   broken_fraction_at_stress = [0.022, 0.31]  # grains broken / grains, and/or
//   bonds_broken_at_stress = [300, 10000]      # bonds broken by stress
//   [crush]                          # single-grain crush tests (dem/breakage/crush.hpp)
//   bonds_broken = 134.0             # mean bonds broken by stress over the tests
//   grains = 30                      # tests, strength seeds 1..grains (default 30)
//   diameter_m = 1.2e-3              # grain diameter (default 1.2 mm)
//   travel = 0.4                     # final platen travel / diameter (default 0.4)
//   [weights]                        # of each misfit in the objective (default 1)
//   stress_strain = 1.0
//   yield_stress = 1.0
//   broken_fraction = 1.0
//   broken_at_stress = 1.0
//   bonds_at_stress = 1.0
//   crush = 1.0
//   [parameters]                     # searched ranges [min, max]
//   sigma_t0_Pa = [6.0e6, 24.0e6]           # breakage.sigma_t0_Pa
//   bond_radius_multiplier = [0.8, 1.6]     # breakage.bond_radius_multiplier
//
// Objective (lower is better, 0 = exact), J = Σ_k w_k m_k over the targets given:
//   m_curve  = RMS_i(σ_run(ε_i) − σ_i) / RMS_i(σ_i), over the target's points
//              (ε_i, σ_i), σ_run linearly interpolated in the run's history
//              (top platen stress against strain); a normalised RMS error.
//   m_yield  = |σ_y,run − σ_y| / σ_y; 1 when the run's curve has no yield.
//   m_broken = RMS_j(f_run(ε_j) − f_j), f = grains broken / initial grains
//              (a fraction already, so not divided again).
//   m_broken_stress = RMS_k(f_run at σ_k − f_k), f_run read at the first
//              history row whose top stress is >= σ_k; 1 for σ_k never reached.
//   m_bonds  = RMS_k min(1, |log10((n_run + 1) / (n_k + 1))|), n = bonds broken
//              by stress at the same rows (the study's Fig. 10: 300 at its
//              2 MPa yield, 10 000 at 4 MPa); a ratio, since bond counts span
//              decades: a factor of 2 scores 0.30, of 10 or more (or σ_k never
//              reached) 1.
//   m_crush  = |b_run − b| / b, b = the mean number of bonds broken by stress
//              over the crush tests, b_run the same tests run with the
//              candidate's parameters (the oedometer bonds' λ acts on the
//              fragments' bonds, which the crush test breaks by the hundred;
//              the oedometer curve hardly sees λ: bench/dem/RESULTS.md).
// A run that stops short of the largest target strain has no objective (NaN).
#pragma once
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "core/table.hpp"

namespace tg::dem::calibration {

struct Parameter {
  std::string name;        // key in [parameters]
  std::string config_key;  // the oedometer config key it sets
  double min = 0, max = 0;
};

// The parameters searched by default: the study's two fitted ones, over
// ranges that bracket Table 1's values by about 2x either way for σ_t0
// (12 MPa) and from PFC's default to past the study's for λ (1.25).
std::vector<Parameter> default_parameters();

struct Target {
  std::string source;  // the target file, for messages and the output
  std::string curve_file;
  std::vector<double> curve_strain, curve_stress_Pa;  // empty: no curve target
  double yield_stress_Pa = 0;                         // 0: no yield target
  std::vector<double> broken_strain, broken_fraction;
  // Grains broken when the top stress first reaches each of these (the
  // study's Fig. 10: 20 of 910 at its 2 MPa yield, 280 at 4 MPa).
  std::vector<double> broken_stress_Pa, broken_fraction_at_stress;
  std::vector<double> bonds_broken_at_stress;  // bonds broken by stress there (empty: no bond target)
  double crush_bonds_broken = 0;  // 0: no crush target
  int crush_grains = 30;
  double crush_diameter_m = 1.2e-3, crush_travel = 0.4;
  double w_curve = 1, w_yield = 1, w_broken = 1, w_broken_stress = 1, w_bonds = 1, w_crush = 1;
  std::vector<Parameter> parameters = default_parameters();
  double largest_strain() const;  // of any target point
};

// InputError naming the file: unreadable, unknown key, no target at all,
// an empty or non-increasing curve, a bad range (min >= max, non-positive),
// negative weights, fractions outside [0, 1], stresses that are not
// positive, lists of unequal length, a crush target that is not
// positive or whose grains, diameter or travel are out of range.
Target read_target(const std::filesystem::path& path);

struct RunScore {
  double curve_misfit = 0, yield_misfit = 0, broken_misfit = 0, broken_stress_misfit = 0, bonds_misfit = 0, crush_misfit = 0;
  double crush_bonds_broken = 0;  // the run's mean over the crush tests (NaN: none run)
  double yield_stress_Pa = 0;   // the run's (NaN when its curve has none)
  double final_strain = 0, peak_stress_Pa = 0, final_broken_fraction = 0;
  double objective = 0;         // NaN when the run is unusable
};

// Scores a run from its history (columns strain, top_stress_Pa and, for a
// broken-fraction target, grains_broken; for a bond target, bonds_broken) and its initial grain count, and,
// for a crush target, the candidate's mean bonds broken over the crush tests
// (NaN, e.g. when the tests failed: no objective).
RunScore score_run(const Target& t, const Table& history, double initial_grains,
                   double crush_bonds_broken = std::numeric_limits<double>::quiet_NaN());

// Linear interpolation of (x, y) at v, x increasing; clamped at the ends.
double interpolate(const std::vector<double>& x, const std::vector<double>& y, double v);

}  // namespace tg::dem::calibration

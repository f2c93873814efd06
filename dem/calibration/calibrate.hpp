// `tomograin dem calibrate CONFIG --target TARGET -o DIR`: fits DEM
// parameters (σ_t0 and λ by default) to a target (dem/calibration/objective.hpp)
// with few full runs, by the search of dem/calibration/surrogate.hpp.
//
// Every run is a child process `tomograin dem oedometer DIR/runs/run_NNN.toml
// -o DIR/runs/run_NNN` (the config with the run's parameters; its log in
// run_NNN.log), up to `jobs` at a time, each single-threaded unless asked
// (OMP_NUM_THREADS). The proposals do not depend on `jobs`: a round's runs
// are independent and its points were fixed before it started.
//
// DIR receives (each file written atomically, rewritten after every round):
//   runs.csv          every run: run, parameters, figures, misfits, objective, status
//   calibration.json  the objective's definition and weights, the ranges, the
//                     search settings, the best run, the surrogate's
//                     hyperparameters and predicted optimum (with its sd)
//   best.toml         the config with the best run's parameters
//   surface.csv       the surrogate's mean and sd of the objective on a 41 x 41
//                     grid of the two parameters
//   objective_surface.png  from surface.csv + runs.csv by plot_calibration.py
// Bad input (config, target, ranges, options) is refused before DIR is made.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

#include "dem/breakage/crush.hpp"
#include "dem/calibration/objective.hpp"
#include "dem/oedometer.hpp"
#include "dem/calibration/surrogate.hpp"

namespace tg::dem::calibration {

struct CalibrateOptions {
  std::filesystem::path config, target, out;
  SearchOptions search;
  int jobs = 1;             // runs at a time (child processes)
  int threads_per_run = 1;  // OMP_NUM_THREADS of each run
  std::string executable;   // the tomograin program (this one: /proc/self/exe)
  std::string python = "/usr/bin/python3";
  std::string plot_script;  // "" = TOMOGRAIN_CALIBRATION_SCRIPT or the source tree's
  bool plot = true;         // false: no objective_surface.png (no Python needed)
  bool quiet = false;
};

struct CalibrationResult {
  SearchResult search;
  Target target;
  std::vector<double> best_parameters, predicted_parameters;  // in the parameters' units
};

// Checks everything a run needs (InputError / UsageError), then runs the
// search. A plotting failure is a ResourceError after every data file exists.
CalibrationResult run_calibration(const CalibrateOptions& o);

// One crush test of a run's model: `setup`'s material, contact, damping and
// breakage options, the grain of `diameter_m` crushed to `travel_fraction` of
// it, strength drawn from `strength_seed`; breakage.d0_m = 0 (the packing's
// mean diameter in the oedometer) is the crush diameter here. The crush term
// below and `tomograin dem crush --model CONFIG` both build their tests here.
breakage::CrushOptions crush_options(const OedometerSetup& setup, double diameter_m, double travel_fraction,
                                     uint64_t strength_seed);

// The mean number of bonds broken by stress over the target's crush tests
// (crush_options above: strength seeds 1..t.crush_grains, diameter and
// travel from the target; a run's config gives the candidate's σ_t0 and λ;
// the crush grain is the reference size). One result per
// entry of `setups`, `threads` tests at a time; each test is single-threaded
// and independent, so the result does not depend on `threads`. A setup with
// a failed test has no mean (NaN: a mean over the other seeds would be a
// different target); the count and the first failure's reason are kept so
// that runs.csv can say why.
struct CrushMean {
  double bonds_broken = 0;  // NaN when a test failed
  int failed = 0;           // tests that threw
  std::string first_failure;  // "strength seed S: what()" of the lowest failed seed
};
std::vector<CrushMean> crush_bonds_broken(const Target& t, const std::vector<OedometerSetup>& setups, int threads);

// The config text of one run: CONFIG with `values` set at the parameters'
// keys and relative paths made absolute (the run's config lives in DIR/runs).
std::string run_config_text(const std::filesystem::path& config, const std::vector<Parameter>& params,
                            const std::vector<double>& values);

}  // namespace tg::dem::calibration

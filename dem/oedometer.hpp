// The oedometer scene of the reference study (§4.2): a pluviated (or read)
// packing in a rigid cylinder, the top platen moving down at constant speed
// to a target axial strain, with history, snapshots and checkpoints.
//
// Strain is measured from H0 = top of the highest grain at the start (as the
// LIGGGHTS peer does; the first few % are seating). Stresses: σ_top and
// σ_bottom = platen force / (π R²); σ_lat = radial force on the cylinder /
// (2π R h) with h the current platen height; K0 = σ_lat / mean(σ_top, σ_bottom).
// Coordination number = 2 × sphere–sphere contacts / spheres.
//
// Run folder: config.toml (copy, by the CLI), run.json (every recorded
// choice: time step and critical step, damping, mass scaling, threads,
// specimen), history.csv, packing_initial.csv, snapshots/strain_X.h5 + .xmf,
// checkpoint.bin (restart continues bit for bit; tested).
// With breakage on, history.csv gains grains_broken, splits_gen0..3 (gen3 =
// generation 3 and above), bonds_broken, bonds_dropped, bonds_intact,
// spheres, particles, volume_lost_m3, time_step_s, fines_removed,
// fines_volume_m3 and added_mass_fraction (splits.csv: one row per split);
// porosity counts the
// lost volume; every snapshot gets a bonds CSV beside it
// (snapshots/strain_X_bonds.csv: sphere_a, sphere_b, normal_force_N, ...);
// particle ids in the snapshot are connected bonded sets; the breakage state
// (bonds with forces and birth steps, sphere keys) travels in the checkpoint.
// breakage.log_bond_breaks adds bond_breaks.csv (a per-process log, like
// splits.csv: bond_breaks_after_restart.csv after a restart).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "dem/breakage/breakage.hpp"
#include "dem/engine.hpp"
#include "dem/pluviation.hpp"

namespace tg::dem {

struct OedometerSetup {
  EngineOptions engine;            // material, contact, damping, walls
  double time_step_safety = 0.2;   // used when time_step_s = 0 (auto)
  double reference_overlap = 0.05; // δ/r_max for the critical step
  double mass_scaling = 1.0;       // multiplies every mass and inertia (recorded)
  std::string packing_csv;         // "" = pluviate with `pluviation`
  PluviationOptions pluviation;
  double platen_speed = 0.1;       // m/s (study)
  double target_strain = 0.1548;   // study's last scan
  std::vector<double> snapshot_strains{0.0, 0.044, 0.0712, 0.1128, 0.1548};
  int64_t history_every = 1000;    // steps between history rows
  int64_t checkpoint_every = 200000;  // steps between checkpoints
  int threads = 0;                 // 0 = OpenMP default
  std::string source = "config";   // the config file, for messages
  // Sequential breakage (issue 7, dem/breakage/): on by default as in Table 1.
  // strength.d0_m = 0 means "the mean grain diameter of the packing"; the
  // bond moduli are taken from the material.
  bool breakage = true;
  // breakage.log_bond_breaks: RUNDIR/bond_breaks.csv, one row per bond broken
  // by stress with its age (dem/run_folder.hpp); off by default.
  bool log_bond_breaks = false;
  breakage::BreakageOptions breakage_options = [] {
    breakage::BreakageOptions b;
    b.strength.d0_m = 0;
    return b;
  }();
};

// Reads every key (defaults from the study), then rejects unknown keys.
// Relative paths are taken from `base_dir` (the config file's folder).
OedometerSetup read_oedometer_config(Config& cfg, const std::filesystem::path& base_dir);

struct RunControl {
  bool restart = false;           // continue from RUNDIR/checkpoint.bin
  int64_t stop_after_steps = -1;  // checkpoint and stop at this step (tests)
  bool quiet = false;             // no progress bar
};

struct OedometerSummary {
  int64_t spheres = 0, steps = 0;
  double time_step = 0, critical_time_step = 0;
  double strain = 0, top_stress_Pa = 0;
  double wall_seconds = 0, particle_steps_per_second = 0;
  double initial_height_m = 0, initial_porosity = 0;
  bool finished = false;          // reached the target strain
  breakage::BreakageRecord breakage;  // zeros when breakage is off
  Particles final_state;
};

OedometerSummary run_oedometer(const OedometerSetup& s, const std::filesystem::path& rundir, const RunControl& c);

}  // namespace tg::dem

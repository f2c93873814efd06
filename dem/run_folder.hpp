// The DEM run folder: its schema is owned here, written by the oedometer
// (dem/oedometer.cpp) and read by everything downstream (compare/, tests)
// through read_run_folder() — nobody else guesses file names.
//
//   RUNDIR/run.json               every choice that changes the physics (JSON)
//   RUNDIR/config.toml            the input config, when the CLI ran it
//   RUNDIR/packing_initial.csv    the spheres at step 0 (core/sphere_table.hpp)
//   RUNDIR/history.csv            one row every history_every steps; the columns
//                                 of history_columns() (+ breakage_columns())
//   RUNDIR/snapshots.csv          the snapshot index, one row per snapshot:
//                                   file             path relative to RUNDIR
//                                   step, time_s     when it was taken
//                                   axial_strain     strain of the specimen then
//                                   requested_strain the strain asked for
//                                   bonds            sidecar of the bonds (relative
//                                                    path), empty without breakage
//   RUNDIR/snapshots/strain_XX.XXpct.h5 (+ .xmf)   spheres (dem/snapshot.hpp)
//   RUNDIR/snapshots/strain_XX.XXpct_bonds.csv     bonds (sphere_a, sphere_b,
//                                   normal_force_N, shear_force_N, twist_moment_Nm,
//                                   bending_moment_Nm; sphere = row of the snapshot)
//   RUNDIR/splits.csv             one row per grain split (step, generation, …)
//   RUNDIR/bond_breaks.csv        with breakage.log_bond_breaks: one row per bond
//                                 broken by stress (step, its age, …)
//   RUNDIR/checkpoint.bin         restart state (dem/checkpoint.hpp)
//
// Strain is axial: (h0 − platen height) / h0, h0 the initial specimen height.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/table.hpp"

namespace tg::dem {

namespace breakage {
class BreakageModel;
struct SplitEvent;
struct BondBreak;
}  // namespace breakage

struct SnapshotEntry {
  std::string file;  // relative to the run folder
  int64_t step = 0;
  double time_s = 0, axial_strain = 0, requested_strain = 0;
  std::string bonds;  // relative path of the bonds sidecar, "" when none
};

// History columns the DEM writes (and the names readers look for).
inline constexpr const char* kHistoryStrain = "strain";
inline constexpr const char* kHistoryTopStress = "top_stress_Pa";
inline constexpr const char* kHistoryGrainsBroken = "grains_broken";
inline constexpr const char* kHistoryBondsBroken = "bonds_broken";

// history.csv as it grows: the base columns, plus breakage_columns() when
// the run breaks grains. Rows are appended in memory and written whole
// (atomically) at each checkpoint; a restart reads back the rows up to its
// checkpoint's step.
class HistoryTable {
 public:
  static const std::vector<std::string>& base_columns();      // step, time_s, strain, top_stress_Pa, …
  static const std::vector<std::string>& breakage_columns();  // grains_broken, splits_gen0..3, …
  explicit HistoryTable(bool breakage);
  // One row; missing trailing values are 0. last(c) edits the last row.
  void add(const std::vector<double>& row);
  double& last(size_t column) { return cols_[column].back(); }
  void write(const std::filesystem::path& path) const;
  void read_until(const std::filesystem::path& path, int64_t step);

 private:
  std::vector<std::string> names_;
  std::vector<std::vector<double>> cols_;
};

// The bonds sidecar of a snapshot (columns in the header above).
void write_bonds_csv(const breakage::BreakageModel& model, const std::filesystem::path& path);
// splits.csv: one row per split (step, time_s, generation, diameter_m, x_m,
// y_m, z_m, f_max_N, stress_Pa, strength_Pa, volume_retained_m3
// + mother_overlap_ratio, fragment_overlap_ratio, fragment_contacts,
// fragment_force_N: the birth figures of breakage::SplitEvent).
void write_splits_csv(const std::vector<breakage::SplitEvent>& events, const std::filesystem::path& path);
// bond_breaks.csv: one row per bond broken by stress (breakage::BondBreak):
// step, time_s, born_step, age_steps, age_s (-1: made before a restart from
// an older checkpoint), generation, radius_a_m, radius_b_m, tensile (1: the
// normal stress reached its strength first, 0: the shear stress).
void write_bond_breaks_csv(const std::vector<breakage::BondBreak>& breaks, const std::filesystem::path& path);

// Writes RUNDIR/snapshots.csv (atomically) from `entries`.
void write_snapshot_index(const std::filesystem::path& rundir, const std::vector<SnapshotEntry>& entries);
// Reads RUNDIR/snapshots.csv; entries with step > max_step are dropped (a
// restart resumes before them). Empty when the file does not exist.
std::vector<SnapshotEntry> read_snapshot_index(const std::filesystem::path& rundir, int64_t max_step = INT64_MAX);

struct RunFolder {
  std::filesystem::path dir;
  std::vector<SnapshotEntry> snapshots;  // in the index's order (increasing strain)
  Table history;                         // empty (no columns) when there is none
  std::filesystem::path snapshot_path(size_t k) const { return dir / snapshots[k].file; }
};

// InputError naming the folder when it is not a DEM run folder (no
// snapshots.csv) or when an indexed file is missing.
RunFolder read_run_folder(const std::filesystem::path& dir);

}  // namespace tg::dem

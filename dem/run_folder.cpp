#include "dem/run_folder.hpp"

#include "core/errors.hpp"
#include "dem/breakage/breakage.hpp"

namespace tg::dem {
namespace fs = std::filesystem;

const std::vector<std::string>& HistoryTable::base_columns() {
  static const std::vector<std::string> n{"step", "time_s", "strain", "top_stress_Pa", "bottom_stress_Pa",
                                          "lateral_stress_Pa", "K0", "kinetic_energy_J", "coordination", "contacts",
                                          "porosity", "platen_z_m"};
  return n;
}

const std::vector<std::string>& HistoryTable::breakage_columns() {
  static const std::vector<std::string> n{"grains_broken", "splits_gen0", "splits_gen1", "splits_gen2", "splits_gen3",
                                          "bonds_broken", "bonds_dropped", "bonds_intact", "spheres", "particles",
                                          "volume_lost_m3", "time_step_s", "fines_removed", "fines_volume_m3",
                                          "added_mass_fraction"};
  return n;
}

HistoryTable::HistoryTable(bool breakage) : names_(base_columns()) {
  if (breakage) names_.insert(names_.end(), breakage_columns().begin(), breakage_columns().end());
  cols_.resize(names_.size());
}

void HistoryTable::add(const std::vector<double>& row) {
  for (size_t c = 0; c < cols_.size(); ++c) cols_[c].push_back(c < row.size() ? row[c] : 0.0);
}

void HistoryTable::write(const fs::path& path) const {
  Table t;
  for (size_t c = 0; c < cols_.size(); ++c) t.add(names_[c], cols_[c]);
  write_csv(t, path);
}

void HistoryTable::read_until(const fs::path& path, int64_t step) {
  if (!fs::exists(path)) return;
  const Table t = read_csv(path, names_);
  for (int64_t r = 0; r < t.rows(); ++r) {
    if (t.num("step")[r] > static_cast<double>(step)) break;
    std::vector<double> row;
    for (const auto& n : names_) row.push_back(t.num(n)[r]);
    add(row);
  }
}

void write_bonds_csv(const breakage::BreakageModel& brk, const fs::path& path) {
  RowTable t({"sphere_a", "sphere_b", "normal_force_N", "shear_force_N", "twist_moment_Nm", "bending_moment_Nm"});
  for (int64_t k = 0; k < brk.bond_count(); ++k) {
    const breakage::BondState& st = brk.bond_state(k);
    t.row({brk.bond_a(k), brk.bond_b(k), st.fn, norm(st.fs), st.mt, norm(st.mb)});
  }
  write_csv(t.table(), path);
}

void write_splits_csv(const std::vector<breakage::SplitEvent>& events, const fs::path& path) {
  RowTable t({"step", "time_s", "generation", "diameter_m", "x_m", "y_m", "z_m", "f_max_N", "stress_Pa", "strength_Pa",
              "volume_retained_m3", "mother_overlap_ratio", "fragment_overlap_ratio", "fragment_contacts",
              "fragment_force_N"});
  for (const breakage::SplitEvent& ev : events)
    t.row({ev.step, ev.time_s, ev.generation, ev.diameter_m, ev.position.x, ev.position.y, ev.position.z, ev.f_max_N,
           ev.stress_Pa, ev.strength_Pa, ev.volume_retained_m3, ev.mother_overlap_ratio, ev.fragment_overlap_ratio,
           ev.fragment_contacts, ev.fragment_force_N});
  write_csv(t.table(), path);
}

void write_bond_breaks_csv(const std::vector<breakage::BondBreak>& breaks, const fs::path& path) {
  RowTable t({"step", "time_s", "born_step", "age_steps", "age_s", "generation", "radius_a_m", "radius_b_m", "tensile"});
  for (const breakage::BondBreak& b : breaks)
    t.row({b.step, b.time_s, b.born_step, b.age_steps, b.age_s, b.generation, b.radius_a_m, b.radius_b_m,
           b.tensile ? 1 : 0});
  write_csv(t.table(), path);
}

void write_snapshot_index(const fs::path& rundir, const std::vector<SnapshotEntry>& entries) {
  RowTable t({"file", "step", "time_s", "axial_strain", "requested_strain", "bonds"});
  for (const SnapshotEntry& e : entries) t.row({e.file, e.step, e.time_s, e.axial_strain, e.requested_strain, e.bonds});
  write_csv(t.table(), rundir / "snapshots.csv");
}

std::vector<SnapshotEntry> read_snapshot_index(const fs::path& rundir, int64_t max_step) {
  const fs::path path = rundir / "snapshots.csv";
  std::vector<SnapshotEntry> out;
  if (!fs::exists(path)) return out;
  const Table t = read_csv(path, {"step", "time_s", "axial_strain", "requested_strain"});
  if (t.rows() == 0) return out;
  // A column of empty cells (no bonds anywhere) reads as text; one of file
  // names too. Both are required.
  const auto& file = t.text("file");
  const auto& bonds = t.text("bonds");
  for (int64_t r = 0; r < t.rows(); ++r) {
    SnapshotEntry e;
    e.file = file[static_cast<size_t>(r)];
    e.step = static_cast<int64_t>(t.num("step")[r]);
    e.time_s = t.num("time_s")[r];
    e.axial_strain = t.num("axial_strain")[r];
    e.requested_strain = t.num("requested_strain")[r];
    e.bonds = bonds[static_cast<size_t>(r)];
    if (e.step > max_step) continue;
    out.push_back(std::move(e));
  }
  return out;
}

RunFolder read_run_folder(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": not a folder (DEM run)");
  if (!fs::exists(dir / "snapshots.csv"))
    throw InputError(dir.string() + ": not a DEM run folder (no snapshots.csv; `tomograin dem oedometer` writes one)");
  RunFolder r;
  r.dir = dir;
  r.snapshots = read_snapshot_index(dir);
  if (r.snapshots.empty()) throw InputError((dir / "snapshots.csv").string() + ": lists no snapshot");
  for (size_t k = 0; k < r.snapshots.size(); ++k)
    if (!fs::exists(r.snapshot_path(k)))
      throw InputError((dir / "snapshots.csv").string() + ": row " + std::to_string(k + 2) + ": " +
                       r.snapshots[k].file + " does not exist");
  if (fs::exists(dir / "history.csv")) r.history = read_csv(dir / "history.csv", {kHistoryStrain, kHistoryTopStress});
  return r;
}

}  // namespace tg::dem

// How XCT stages and DEM snapshots are paired, and how the broken fraction of
// each series is obtained — the comparison's decisions, apart from its I/O so
// that they are tested on their own.
//
//   match_snapshot   the snapshot whose strain is nearest the stage's when both
//                    are known; else the stage's index (clamped to the last
//                    snapshot): stage n ↔ snapshot n
//   broken fraction  DEM: the history's grains_broken at the snapshot's strain
//                    (linear between rows) over the initial particles; without
//                    that column, the growth of the particle count (one extra
//                    particle per break), clamped to [0, 1]. Experiment: the
//                    synthetic truth when the scan has one, else the growth of
//                    the particle count against stage 0 (the tracking issue
//                    replaces that estimate by the lineage).
//   curves           strain and axial stress (MPa) of an experimental CSV
//                    (flexible column names, unit from the suffix) or of the
//                    DEM history (dem/run_folder.hpp's columns).
#pragma once
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "core/table.hpp"

namespace tg::compare {

size_t match_snapshot(std::span<const double> snapshot_strains, double stage_strain, size_t stage_index);

struct Curve {
  std::vector<double> strain, stress_mpa, broken;  // broken (grains broken, a count) empty when absent
  std::vector<double> bonds;                      // bonds broken (DEM history); empty when absent
  std::string stress_column;
};
// An experimental stress–strain CSV: strain column axial_strain|strain|eps_zz|strain_zz,
// stress axial_stress_{Pa,kPa,MPa}|stress_zz_Pa|sigma_zz_Pa|top_stress_Pa|stress_{Pa,kPa,MPa}
// (else the first column whose name holds "stress", in Pa), optional
// grains_broken|broken_grains|broken_particles|broken.
Curve read_curve(const std::filesystem::path& path);
// The DEM history table (strain, top_stress_Pa, optional grains_broken and bonds_broken).
Curve history_curve(const Table& history);

// y at x = at: linear between the bracketing rows where x ascends there,
// else the nearest row; NaN for an empty curve.
double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at);

// (count − count0) / count0 clamped to [0, 1]; NaN when count0 is 0.
double count_growth_fraction(int64_t count, int64_t count0);

struct BrokenEstimate {
  double fraction = 0;
  std::string method;
};
// The DEM's broken fraction at a snapshot of strain `strain` holding
// `particles` particles, `initial` at the start (see above).
BrokenEstimate dem_broken_fraction(const Curve& history, double strain, int64_t particles, int64_t initial);

}  // namespace tg::compare

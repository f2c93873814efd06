// The report folder's files (listed in compare/comparison.hpp): the CSV
// tables behind every plot, report.json, the mid-slices as .npy, and the
// plotting script's run. Every file is written atomically
// (core/atomic_file.hpp); class labels come from measure/grading.hpp.
#pragma once
#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "compare/comparison.hpp"
#include "compare/imaging_estimate.hpp"
#include "compare/series.hpp"
#include "compare/stage_matching.hpp"
#include "core/volume.hpp"

namespace tg::compare {

// Series names in the tables, in this order.
inline constexpr const char* kSeriesNames[3] = {"experiment", "dem_ideal", "dem_imaged"};
// The DEM's exact contacts (from its spheres) in the contact tables.
inline constexpr const char* kExactSeriesName = "dem_exact";

// Everything the files are made from. Per stage: the three series
// (dem_imaged nullptr when that path is off), the DEM's exact contacts and
// particle shapes (shape_classes.csv's dem_exact rows: every particle, no
// detection limit; compare/dem_stage.hpp exact_shape_sample), and
// the grey-level estimate of the experiment's scan (nullptr for particle-table inputs).
struct ReportData {
  const Report* report = nullptr;
  std::vector<std::array<const Series*, 3>> series;
  std::vector<const ContactSeries*> exact;
  std::vector<const measure::GradingSample*> exact_shapes;  // every DEM particle's shape from its spheres (may be empty)
  std::vector<const GreyEstimate*> grey;
  Curve history, experiment_curve;
  int64_t initial_dem_particles = 0;
};

// summary.csv, psd.csv, shape_classes.csv, distances.csv, stress_strain.csv, broken.csv,
// and the contact tables: fabric.csv, normals.csv, coordination_by_size.csv,
// contacts/STAGE_SERIES.csv (compare/fabric.hpp).
void write_report_tables(const std::filesystem::path& dir, const ReportData& d);
// lineage.csv (events and breakage by height per stage: experiment, dem_exact,
// dem_imaged, whichever exist) and tracker_bias.csv (when rep.tracker_bias);
// called by write_report_tables.
void write_lineage_tables(const std::filesystem::path& dir, const Report& rep);
// report.json's "dem_lineage": the folders, the note, the tracker's bias on DEM data.
nlohmann::json lineage_json(const Report& rep);
// report.json: `meta` (inputs and options, filled by the caller) plus the stages.
void write_report_json(const std::filesystem::path& dir, const ReportData& d, nlohmann::json meta);
// The three orthogonal mid-slices of a volume as DIR/STEM_{z,y,x}.npy
// (NumPy format 1.0; u16 or u32).
template <class T>
void write_mid_slices(const Volume<T>& v, const std::filesystem::path& dir, const std::string& stem);
// Runs `python script dir` (compare/report/make_report.py) and returns
// dir/index.html; ResourceError when the script is missing or fails.
std::filesystem::path run_plot_script(const std::filesystem::path& dir, const std::string& python,
                                      const std::string& script);

}  // namespace tg::compare

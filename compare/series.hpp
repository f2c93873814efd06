// One measured series of one loading stage — the experiment, the DEM's ideal
// path (truth labels) or its imaged path (segmented) — as the comparison
// carries it from measuring to the report files.
#pragma once
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "core/table.hpp"
#include "core/volume.hpp"
#include "measure/grading.hpp"
#include "measure/particles.hpp"

namespace tg::compare {

struct Series {
  Table particles;                  // tomograin measure's particle table
  measure::GradingSample sample;    // what the grading and the distances see
  measure::StageGrading metrics;    // filled once every stage is measured (common sieves)
  double broken_fraction = std::numeric_limits<double>::quiet_NaN();
  std::string broken_method;        // how broken_fraction was obtained, shown in the report
  nlohmann::json info = nlohmann::json::object();  // provenance for report.json
};

// The particle table of a label volume (measure/particles.hpp).
inline Table measure_labels(const Volume<uint32_t>& labels, const measure::ParticleOptions& po) {
  return measure::particle_table(measure::measure_particles(labels.view(), po));
}

}  // namespace tg::compare

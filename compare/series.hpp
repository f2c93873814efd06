// One measured series of one loading stage — the experiment, the DEM's ideal
// path (truth labels) or its imaged path (segmented) — as the comparison
// carries it from measuring to the report files.
#pragma once
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "compare/fabric.hpp"
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
  double coordination = std::numeric_limits<double>::quiet_NaN();  // mean over interior particles
  ContactSeries contacts;           // fabric, normals, coordination by size (compare/fabric.hpp)
  nlohmann::json info = nlohmann::json::object();  // provenance for report.json
};

// Mean coordination (measure/contacts.hpp, from the labels) of the particles
// that do not touch the volume's border (their neighbours outside are
// unseen); NaN without a coordination column or interior particle.
inline double mean_interior_coordination(const Table& t) {
  if (!t.has("coordination") || !t.has("touches_border")) return std::numeric_limits<double>::quiet_NaN();
  const auto &z = t.num("coordination"), &b = t.num("touches_border");
  double sum = 0;
  int64_t n = 0;
  for (int64_t q = 0; q < t.rows(); ++q)
    if (b[q] == 0 && z[q] >= 0) sum += z[q], ++n;
  return n ? sum / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

// Measures a label volume into `s`: the particle table (measure/particles.hpp),
// its grading sample, the mean interior coordination and, when po.contacts,
// the contact series. The contacts are searched once: measure_particles runs
// without them and its coordination column is filled from this search.
// With `grey` (the scan the labels were segmented from) the volumes are the
// grey-level estimates that `analyse` and `measure --grey` report
// (measure/grey_volume.hpp; the phases' levels from the scan's histogram),
// so a comparison reads the same volumes as an analysis of the same scan.
void measure_series(const Volume<uint32_t>& labels, const measure::ParticleOptions& po, Series& s,
                    const Volume<uint16_t>* grey = nullptr);

}  // namespace tg::compare

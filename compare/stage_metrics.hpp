// What the comparison measures on one loading stage's particle table, for
// the experiment and for both DEM paths alike (reference study §4.3):
//   PSD by mass on Dmed (percent passing at sieves, log-linear between them),
//   D10 / D50 / D60 / Cu, FR and AR class percentages in the study's bins
//   (measure/psd.hpp: FR < 0.4, 0.4–0.8, 0.8–0.9, ≥ 0.9; AR < 2, 2–3, ≥ 3),
//   Hardin's relative breakage against the series' first stage, and the
//   KS / W1 distances (compare/distances.hpp) between two stages' samples:
//   PSD: Dmed weighted by volume (= mass, uniform density); FR, AR: one
//   weight per particle.
// Particles flagged below the detection limit (below_limit = 1) count in the
// PSD (their mass is real) but not in FR/AR (their shape is not resolved).
#pragma once
#include <span>
#include <string>
#include <vector>

#include "core/table.hpp"

namespace tg::compare {

struct StageSample {
  std::vector<double> dmed_mm, volume_mm3;  // every particle
  std::vector<double> fr, ar;               // resolved particles only
};

// From a particle table (measure::particle_table columns d_med_mm,
// volume_mm3, fr, ar and optionally below_limit). Rows with volume <= 0 or a
// non-finite Dmed are dropped.
StageSample sample_from_table(const Table& particles);

// R10 sieves (10^(k/10) mm) covering 0.1–2.5 mm and every size in `samples`:
// the largest sieve passes 100 % (measure/psd.hpp requires it).
std::vector<double> sieves_for(std::span<const StageSample* const> samples);

struct StageMetrics {
  int64_t particles = 0;
  std::vector<double> passing;  // percent passing at each sieve
  double d10 = 0, d50 = 0, d60 = 0, cu = 0;
  std::vector<double> fr_classes, ar_classes;  // percent per class
  double hardin_br = 0;  // filled by the caller against the first stage
};
StageMetrics stage_metrics(const StageSample& s, std::span<const double> sieves);

struct Distances {
  double psd_ks = 0, psd_w1_mm = 0, fr_ks = 0, fr_w1 = 0, ar_ks = 0, ar_w1 = 0;
};
// NaN for a distribution that is empty on either side.
Distances sample_distances(const StageSample& a, const StageSample& b);

}  // namespace tg::compare

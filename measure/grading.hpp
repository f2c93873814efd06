// The grading of loading stages: the ONE implementation behind `tomograin
// psd` and the comparison report (compare/), so both print the same numbers
// for the same particle table. Primitives (percent passing, Hardin, Einav,
// class histograms) are in measure/psd.hpp.
//
// Which particles count (stated once, here):
//   * rows with volume <= 0 or a size that is not finite and > 0 are dropped;
//   * particles flagged below the detection limit (`below_limit` = 1) count in
//     the mass-based PSD and D-values (their mass is real) but NOT in the FR
//     and AR classes (their shape is not resolved). `exclude_below_limit`
//     leaves them out of everything; `exclude_border` drops particles that
//     touch the volume's border.
//
// D-values (D10, D50, D60, Cu = D60/D10) come from the sorted particle table,
// not from sieves, so they exist whatever the sieve set and do not depend on
// it: particles sorted by size d_1 <= ... <= d_n with masses m_i, cumulative
// percent passing F_i = 100 Σ_{j<=i} m_j / M (the grading with a sieve at
// every particle size); D_p is log-linear between the two particles that
// bracket p, and d_1 when p <= F_1 (nothing is known below the finest
// particle). Equal sizes merge. The sieve curve (percent passing at sieves)
// is for plots and for Hardin's and Einav's integrals.
//
// Sieves: by default the R40 series 10^(k/40) mm (ratio 1.059) from 0.1 to
// 2.5 mm — fine enough for a grading as narrow as the study's (Cu 1.07, about
// six sieves between D10 and D60); a user's set replaces it. Either set is
// extended by R40 sizes so that the largest sieve passes 100 % (Hardin and
// Einav need it) and the smallest lies at or below the finest particle.
//
// FR and AR classes: the reference study's (Figs. 13–14): FR < 0.4, 0.4–0.8,
// 0.8–0.9, >= 0.9; AR < 2, 2–3, >= 3; labels from class_labels() ("<0.4",
// "0.4-0.8", …) and CSV column names from class_columns() ("fr_lt_0.4_pct", …).
//
// Breakage indices compare each stage with the first one given: Hardin's Br
// (cut-off `hardin_cutoff_mm`) and Einav's Br* (measure/psd.hpp).
#pragma once
#include <span>
#include <string>
#include <vector>

#include "core/table.hpp"
#include "measure/psd.hpp"

namespace tg::measure {

// The particles of one stage as a grading sees them.
struct GradingSample {
  std::vector<double> size_mm, mass;  // every counted particle: d_med, volume (mass at uniform density)
  std::vector<double> deq_mm;         // d_eq of the same particles (empty when the table has none)
  std::vector<double> fr, ar;         // resolved particles only (see above)
};

struct SampleRules {
  bool exclude_below_limit = false;  // drop below-limit particles from everything
  bool exclude_border = false;       // drop particles touching the volume's border
};

// From a particle table of `tomograin measure` (d_med_mm, volume_mm3, fr, ar;
// optional d_eq_mm, below_limit, touches_border).
GradingSample grading_sample(const Table& particles, const SampleRules& rules = {});

// Mass-weighted quantile of the sorted table (see above), NaN when empty.
double sorted_quantile(std::span<const double> sizes, std::span<const double> masses, double p);
GradingSummary sorted_summary(std::span<const double> sizes, std::span<const double> masses);

// R40 sizes 10^(k/40) mm from 0.1 to 2.5 mm.
std::vector<double> default_sieves_mm();
// `base` (default_sieves_mm() when empty) sorted, extended by R40 sizes so
// that it covers every size of every sample (see above).
std::vector<double> sieves_covering(std::span<const double> base, std::span<const GradingSample* const> samples);

// "<0.4", "0.4-0.8", "0.8-0.9", ">=0.9" for thresholds {0.4, 0.8, 0.9}.
std::vector<std::string> class_labels(std::span<const double> thresholds);
// "fr_lt_0.4_pct", "fr_0.4_0.8_pct", …, "fr_ge_0.9_pct".
std::vector<std::string> class_columns(const std::string& metric, std::span<const double> thresholds);

struct GradingOptions {
  std::vector<double> fr_bins = fr_thresholds(), ar_bins = ar_thresholds();
  double hardin_cutoff_mm = 0.074;
  EinavOptions einav;
};

struct StageGrading {
  int64_t particles = 0;
  double mass = 0;                          // Σ volume, mm³
  std::vector<double> passing, passing_eq;  // percent passing at each sieve (by d_med; by d_eq if known)
  GradingSummary d;                         // from the sorted table (NaN when empty)
  double d50_eq = 0;                        // sorted-table D50 of d_eq (NaN without d_eq)
  std::vector<double> fr_classes, ar_classes;  // percent of resolved particles per class
  double hardin_br = 0, einav_br = 0;          // against the first stage (NaN if either is empty)
};

// Every stage on the same `sieves` (from sieves_covering over all of them).
// An empty stage gives NaN passing and D-values rather than an error.
std::vector<StageGrading> grade_stages(std::span<const GradingSample> stages, std::span<const double> sieves,
                                       const GradingOptions& opt = {});

}  // namespace tg::measure

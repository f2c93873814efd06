// Distances between two weighted one-dimensional samples: the
// Kolmogorov–Smirnov statistic and the Wasserstein-1 (earth mover's)
// distance. Used to compare experiment and simulation per loading stage:
// the PSD by mass (sample = Dmed, weight = particle volume) and the FR and AR
// distributions (weight 1 per particle).
//
// With the weighted empirical CDFs F_a(x) = Σ_{a_i <= x} w_i / Σ w_i (right
// continuous, a step at every sample value):
//   KS = sup_x |F_a(x) − F_b(x)|            (in [0, 1])
//   W1 = ∫ |F_a(x) − F_b(x)| dx               (units of x)
// Both are evaluated exactly by one merge of the two sorted samples: between
// consecutive distinct values both CDFs are constant, so the sup is taken at
// the values and the integral is a sum of rectangles. W1 equals
// scipy.stats.wasserstein_distance(a, b, wa, wb) and KS equals the statistic
// of scipy.stats.ks_2samp for unit weights (tested against both).
// Reference: Villani, Optimal Transport (2009), Remark 2.19 (W1 on the line
// as the L1 distance between CDFs). Cost O((n+m) log(n+m)) for the sort.
#pragma once
#include <span>

#include "measure/grading.hpp"

namespace tg::compare {

// Throws UsageError when a sample is empty, sizes differ, a value is not
// finite, a weight is negative or not finite, or all weights are zero.
// Empty weight spans mean unit weights.
double ks_distance(std::span<const double> a, std::span<const double> b, std::span<const double> wa = {},
                   std::span<const double> wb = {});
double wasserstein1(std::span<const double> a, std::span<const double> b, std::span<const double> wa = {},
                    std::span<const double> wb = {});

// The distances the report shows between two stages' samples
// (measure/grading.hpp): PSD = d_med weighted by mass; FR, AR by number.
struct Distances {
  double psd_ks = 0, psd_w1_mm = 0, fr_ks = 0, fr_w1 = 0, ar_ks = 0, ar_w1 = 0;
};
// NaN for a distribution that is empty on either side.
Distances sample_distances(const measure::GradingSample& a, const measure::GradingSample& b);

}  // namespace tg::compare

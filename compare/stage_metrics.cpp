#include "compare/stage_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "compare/distances.hpp"
#include "core/errors.hpp"
#include "measure/psd.hpp"

namespace tg::compare {

StageSample sample_from_table(const Table& t) {
  const auto &d = t.num("d_med_mm"), &v = t.num("volume_mm3"), &fr = t.num("fr"), &ar = t.num("ar");
  const std::vector<double>* below = t.has("below_limit") ? &t.num("below_limit") : nullptr;
  StageSample s;
  for (int64_t q = 0; q < t.rows(); ++q) {
    if (!(v[q] > 0) || !std::isfinite(d[q]) || !(d[q] > 0)) continue;
    s.dmed_mm.push_back(d[q]);
    s.volume_mm3.push_back(v[q]);
    if (below && (*below)[q] != 0) continue;
    if (std::isfinite(fr[q]) && std::isfinite(ar[q]) && fr[q] > 0 && ar[q] > 0) {
      s.fr.push_back(fr[q]);
      s.ar.push_back(ar[q]);
    }
  }
  return s;
}

std::vector<double> sieves_for(std::span<const StageSample* const> samples) {
  double lo = 0.1, hi = 2.5;
  for (const StageSample* s : samples)
    for (double d : s->dmed_mm) {
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  // R10: k/10 decades; a little slack so a size on a sieve is passed by it.
  const int k0 = static_cast<int>(std::floor(10 * std::log10(lo) + 1e-9));
  const int k1 = static_cast<int>(std::ceil(10 * std::log10(hi * (1 + 1e-12))));
  std::vector<double> out;
  for (int k = k0; k <= k1; ++k) out.push_back(std::pow(10.0, k / 10.0));
  if (out.back() < hi) out.push_back(out.back() * std::pow(10.0, 0.1));
  return out;
}

StageMetrics stage_metrics(const StageSample& s, std::span<const double> sieves) {
  StageMetrics m;
  m.particles = static_cast<int64_t>(s.dmed_mm.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (s.dmed_mm.empty()) {
    m.passing.assign(sieves.size(), nan);
    m.d10 = m.d50 = m.d60 = m.cu = nan;
  } else {
    m.passing = measure::percent_passing(s.dmed_mm, s.volume_mm3, sieves);
    const auto g = measure::grading_summary(sieves, m.passing);
    m.d10 = g.d10;
    m.d50 = g.d50;
    m.d60 = g.d60;
    m.cu = g.cu;
  }
  m.fr_classes = measure::class_percent(s.fr, measure::fr_thresholds());
  m.ar_classes = measure::class_percent(s.ar, measure::ar_thresholds());
  return m;
}

Distances sample_distances(const StageSample& a, const StageSample& b) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Distances d{nan, nan, nan, nan, nan, nan};
  if (!a.dmed_mm.empty() && !b.dmed_mm.empty()) {
    d.psd_ks = ks_distance(a.dmed_mm, b.dmed_mm, a.volume_mm3, b.volume_mm3);
    d.psd_w1_mm = wasserstein1(a.dmed_mm, b.dmed_mm, a.volume_mm3, b.volume_mm3);
  }
  if (!a.fr.empty() && !b.fr.empty()) {
    d.fr_ks = ks_distance(a.fr, b.fr);
    d.fr_w1 = wasserstein1(a.fr, b.fr);
    d.ar_ks = ks_distance(a.ar, b.ar);
    d.ar_w1 = wasserstein1(a.ar, b.ar);
  }
  return d;
}

}  // namespace tg::compare

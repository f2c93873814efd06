#include "measure/grading.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/errors.hpp"

namespace tg::measure {
namespace {

constexpr double kR40 = 40;  // sizes 10^(k/40) mm

double r40(int k) { return std::pow(10.0, k / kR40); }

// Einav's integrals need a range: the smallest size below the initial
// grading's largest (its first sieve passing 100 %). A stage-0 grading of
// one size sitting on the finest sieve has none: Br* is then undefined (NaN).
bool einav_defined(std::span<const double> s, std::span<const double> initial, const EinavOptions& o) {
  size_t kM = 0;
  while (kM < s.size() && initial[kM] < 100.0 - 1e-9) ++kM;
  return kM < s.size() && (o.d_min > 0 ? o.d_min : s.front()) < s[kM];
}

}  // namespace

GradingSample grading_sample(const Table& t, const SampleRules& rules) {
  const auto &d = t.num("d_med_mm"), &v = t.num("volume_mm3"), &fr = t.num("fr"), &ar = t.num("ar");
  const std::vector<double>* deq = t.has("d_eq_mm") ? &t.num("d_eq_mm") : nullptr;
  const std::vector<double>* below = t.has("below_limit") ? &t.num("below_limit") : nullptr;
  const std::vector<double>* border = t.has("touches_border") ? &t.num("touches_border") : nullptr;
  GradingSample s;
  for (int64_t q = 0; q < t.rows(); ++q) {
    if (!(v[q] > 0) || !std::isfinite(v[q]) || !std::isfinite(d[q]) || !(d[q] > 0)) continue;
    const bool is_below = below && (*below)[q] != 0;
    if ((rules.exclude_below_limit && is_below) || (rules.exclude_border && border && (*border)[q] != 0)) continue;
    s.size_mm.push_back(d[q]);
    s.mass.push_back(v[q]);
    if (deq) s.deq_mm.push_back((*deq)[q]);
    if (is_below) continue;
    if (std::isfinite(fr[q]) && std::isfinite(ar[q]) && fr[q] > 0 && ar[q] > 0) {
      s.fr.push_back(fr[q]);
      s.ar.push_back(ar[q]);
    }
  }
  return s;
}

double sorted_quantile(std::span<const double> sizes, std::span<const double> masses, double p) {
  if (sizes.size() != masses.size()) throw UsageError("grading: sizes and masses differ in length");
  if (sizes.empty()) return kNaN;
  std::vector<size_t> order(sizes.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return sizes[a] < sizes[b]; });
  double total = 0;
  for (double m : masses) total += m;
  if (!(total > 0)) return kNaN;
  // Walk the distinct sizes: (d_prev, F_prev) -> (d, F).
  double d_prev = sizes[order[0]], f_prev = -1, cum = 0;
  for (size_t q = 0; q < order.size();) {
    const double d = sizes[order[q]];
    while (q < order.size() && sizes[order[q]] == d) cum += masses[order[q++]];
    const double f = 100.0 * cum / total;
    if (f >= p) {
      if (f_prev < 0) return d;  // at or below the finest particle's share
      const double t = (p - f_prev) / (f - f_prev);
      return d_prev * std::pow(d / d_prev, t);
    }
    d_prev = d;
    f_prev = f;
  }
  return d_prev;  // p > 100 (rounding): the largest size
}

GradingSummary sorted_summary(std::span<const double> sizes, std::span<const double> masses) {
  GradingSummary g;
  g.d10 = sorted_quantile(sizes, masses, 10);
  g.d50 = sorted_quantile(sizes, masses, 50);
  g.d60 = sorted_quantile(sizes, masses, 60);
  g.cu = g.d60 / g.d10;
  return g;
}

std::vector<double> default_sieves_mm() {
  std::vector<double> s;
  for (int k = -40; k <= 16; ++k) s.push_back(r40(k));  // 0.1 ... 2.51 mm
  return s;
}

std::vector<double> sieves_covering(std::span<const double> base, std::span<const GradingSample* const> samples) {
  std::vector<double> s(base.begin(), base.end());
  if (s.empty()) s = default_sieves_mm();
  std::sort(s.begin(), s.end());
  s.erase(std::unique(s.begin(), s.end()), s.end());
  if (!(s.front() > 0)) throw UsageError("grading: sieve sizes must be > 0");
  double lo = std::numeric_limits<double>::max(), hi = 0;
  for (const GradingSample* g : samples)
    for (double d : g->size_mm) {
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  // A little slack so that a size lying on an R40 size is passed by it.
  if (hi > s.back()) {
    const int k1 = static_cast<int>(std::ceil(kR40 * std::log10(hi) - 1e-9));
    for (int k = static_cast<int>(std::floor(kR40 * std::log10(s.back()))) + 1; k <= k1; ++k)
      if (r40(k) > s.back()) s.push_back(r40(k));
    if (s.back() < hi) s.push_back(r40(k1 + 1));
  }
  if (lo < s.front()) {
    std::vector<double> below;
    const int k0 = static_cast<int>(std::floor(kR40 * std::log10(lo) + 1e-9));
    for (int k = k0; r40(k) < s.front() * (1 - 1e-12); ++k) below.push_back(r40(k));
    s.insert(s.begin(), below.begin(), below.end());
  }
  return s;
}

std::vector<std::string> class_labels(std::span<const double> t) {
  std::vector<std::string> n;
  if (t.empty()) return {"all"};
  n.push_back(fmt::format("<{:g}", t.front()));
  for (size_t k = 1; k < t.size(); ++k) n.push_back(fmt::format("{:g}-{:g}", t[k - 1], t[k]));
  n.push_back(fmt::format(">={:g}", t.back()));
  return n;
}

std::vector<std::string> class_columns(const std::string& metric, std::span<const double> t) {
  std::vector<std::string> n;
  if (t.empty()) return {metric + "_all_pct"};
  n.push_back(fmt::format("{}_lt_{:g}_pct", metric, t.front()));
  for (size_t k = 1; k < t.size(); ++k) n.push_back(fmt::format("{}_{:g}_{:g}_pct", metric, t[k - 1], t[k]));
  n.push_back(fmt::format("{}_ge_{:g}_pct", metric, t.back()));
  return n;
}

std::vector<StageGrading> grade_stages(std::span<const GradingSample> stages, std::span<const double> sieves,
                                       const GradingOptions& opt) {
  std::vector<StageGrading> out;
  for (const GradingSample& s : stages) {
    StageGrading g;
    g.particles = static_cast<int64_t>(s.size_mm.size());
    for (double m : s.mass) g.mass += m;
    const bool empty = s.size_mm.empty();
    g.passing = empty ? std::vector<double>(sieves.size(), kNaN) : percent_passing(s.size_mm, s.mass, sieves);
    const bool has_eq = !empty && s.deq_mm.size() == s.size_mm.size();
    g.passing_eq = has_eq ? percent_passing(s.deq_mm, s.mass, sieves) : std::vector<double>(sieves.size(), kNaN);
    g.d = empty ? GradingSummary{kNaN, kNaN, kNaN, kNaN} : sorted_summary(s.size_mm, s.mass);
    g.d50_eq = has_eq ? sorted_quantile(s.deq_mm, s.mass, 50) : kNaN;
    g.fr_classes = class_percent(s.fr, opt.fr_bins);
    g.ar_classes = class_percent(s.ar, opt.ar_bins);
    const StageGrading& first = out.empty() ? g : out.front();
    const bool both = !empty && !stages.front().size_mm.empty();
    g.hardin_br = both ? hardin_br(sieves, first.passing, g.passing, opt.hardin_cutoff_mm) : kNaN;
    g.einav_br = both && einav_defined(sieves, first.passing, opt.einav) ? einav_br(sieves, first.passing, g.passing, opt.einav)
                                                                        : kNaN;
    out.push_back(std::move(g));
  }
  return out;
}

}  // namespace tg::measure

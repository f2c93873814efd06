#include "compare/distances.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "core/errors.hpp"

namespace tg::compare {
namespace {

// A sample sorted by value with normalised weights.
struct Sorted {
  std::vector<double> x, w;
};

Sorted prepare(std::span<const double> v, std::span<const double> w, const char* which) {
  if (v.empty()) throw UsageError(std::string("distance: sample ") + which + " is empty");
  if (!w.empty() && w.size() != v.size())
    throw UsageError(std::string("distance: sample ") + which + " has " + std::to_string(v.size()) + " values but " +
                     std::to_string(w.size()) + " weights");
  std::vector<size_t> order(v.size());
  std::iota(order.begin(), order.end(), size_t{0});
  double total = 0;
  for (size_t q = 0; q < v.size(); ++q) {
    const double wq = w.empty() ? 1.0 : w[q];
    if (!std::isfinite(v[q])) throw UsageError(std::string("distance: sample ") + which + " has a non-finite value");
    if (!(wq >= 0) || !std::isfinite(wq))
      throw UsageError(std::string("distance: sample ") + which + " has a negative or non-finite weight");
    total += wq;
  }
  if (!(total > 0)) throw UsageError(std::string("distance: sample ") + which + " has zero total weight");
  // stable_sort: equal values keep input order, so sums are reproducible.
  std::stable_sort(order.begin(), order.end(), [&](size_t p, size_t q) { return v[p] < v[q]; });
  Sorted s;
  s.x.reserve(v.size());
  s.w.reserve(v.size());
  for (size_t q : order) {
    s.x.push_back(v[q]);
    s.w.push_back((w.empty() ? 1.0 : w[q]) / total);
  }
  return s;
}

// Walks the union of the sample values in ascending order; at every distinct
// value x (after both CDFs have stepped there) calls f(x, Fa(x), Fb(x)).
template <class F>
void walk(const Sorted& a, const Sorted& b, F&& f) {
  size_t p = 0, q = 0;
  double fa = 0, fb = 0;
  while (p < a.x.size() || q < b.x.size()) {
    const double x = q >= b.x.size() || (p < a.x.size() && a.x[p] <= b.x[q]) ? a.x[p] : b.x[q];
    while (p < a.x.size() && a.x[p] == x) fa += a.w[p++];
    while (q < b.x.size() && b.x[q] == x) fb += b.w[q++];
    // The last step reaches 1 up to rounding; pin it so KS of equal samples is 0.
    if (p == a.x.size()) fa = 1;
    if (q == b.x.size()) fb = 1;
    f(x, fa, fb);
  }
}

}  // namespace

double ks_distance(std::span<const double> a, std::span<const double> b, std::span<const double> wa,
                   std::span<const double> wb) {
  const Sorted sa = prepare(a, wa, "a"), sb = prepare(b, wb, "b");
  double d = 0;
  walk(sa, sb, [&](double, double fa, double fb) { d = std::max(d, std::abs(fa - fb)); });
  return d;
}

double wasserstein1(std::span<const double> a, std::span<const double> b, std::span<const double> wa,
                    std::span<const double> wb) {
  const Sorted sa = prepare(a, wa, "a"), sb = prepare(b, wb, "b");
  double d = 0, prev_x = 0, prev_diff = 0;
  bool first = true;
  walk(sa, sb, [&](double x, double fa, double fb) {
    if (!first) d += prev_diff * (x - prev_x);
    first = false;
    prev_x = x;
    prev_diff = std::abs(fa - fb);
  });
  return d;
}

Distances sample_distances(const measure::GradingSample& a, const measure::GradingSample& b) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Distances d{nan, nan, nan, nan, nan, nan};
  if (!a.size_mm.empty() && !b.size_mm.empty()) {
    d.psd_ks = ks_distance(a.size_mm, b.size_mm, a.mass, b.mass);
    d.psd_w1_mm = wasserstein1(a.size_mm, b.size_mm, a.mass, b.mass);
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

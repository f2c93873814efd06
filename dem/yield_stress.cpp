#include "dem/yield_stress.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

namespace tg::dem {
namespace yield_detail {

struct Line {
  double a = 0, b = 0, sse = 0;  // y = a + b x
};

Line fit(const std::vector<double>& x, const std::vector<double>& y, size_t i0, size_t i1) {
  double n = static_cast<double>(i1 - i0), sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = i0; i < i1; ++i) {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  Line l;
  const double d = n * sxx - sx * sx;
  l.b = d != 0 ? (n * sxy - sx * sy) / d : 0;
  l.a = (sy - l.b * sx) / n;
  for (size_t i = i0; i < i1; ++i) l.sse += std::pow(y[i] - l.a - l.b * x[i], 2);
  return l;
}

}  // namespace yield_detail

// Oedometer curves of crushable sands steepen 3-10 times past yield
// (compression over recompression index; the DEM runs of bench/dem 7-10).
constexpr double kKneeRatio = 1.5;

double yield_stress_mpa(const std::vector<double>& strain, const std::vector<double>& stress_mpa, double floor_mpa) {
  using yield_detail::fit;
  using yield_detail::Line;
  std::vector<double> x, y;  // log10 stress, strain: the curve up to its peak (unloading and drops left out)
  double peak = 0;
  for (size_t i = 0; i < strain.size() && i < stress_mpa.size(); ++i) {
    if (!(stress_mpa[i] > floor_mpa) || !(stress_mpa[i] > peak)) continue;
    peak = stress_mpa[i];
    x.push_back(std::log10(stress_mpa[i]));
    y.push_back(strain[i]);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (x.size() < 6) return nan;
  double best = std::numeric_limits<double>::infinity(), yield = nan;
  for (size_t k = 3; k + 3 <= x.size(); ++k) {
    const Line a = fit(x, y, 0, k), b = fit(x, y, k, x.size());
    // A knee of compression: the soft branch steeper than the stiff one by
    // kKneeRatio at least. Without it a straight line (no yield) still gave
    // a "yield" where two fits of equal slope happened to cross, and a curve
    // that stiffens gave one where it stiffens.
    if (!(a.sse + b.sse < best) || !(b.b > 0) || !(b.b >= kKneeRatio * a.b)) continue;
    // Two lines that meet outside the fitted stresses describe no yield.
    const double meet = (a.a - b.a) / (b.b - a.b);
    if (meet < x.front() || meet > x.back()) continue;
    best = a.sse + b.sse;
    yield = std::pow(10.0, meet);
  }
  return yield;
}

}  // namespace tg::dem

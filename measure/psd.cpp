#include "measure/psd.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/errors.hpp"

namespace tg::measure {
namespace {

void check_sieves(std::span<const double> s) {
  if (s.empty()) throw UsageError("PSD: no sieve sizes");
  for (size_t k = 0; k < s.size(); ++k)
    if (!(s[k] > 0) || (k > 0 && !(s[k] > s[k - 1])))
      throw UsageError("PSD: sieve sizes must be positive and strictly ascending");
}

void check_curve(std::span<const double> s, std::span<const double> p, const char* what) {
  if (p.size() != s.size()) throw UsageError(std::string("PSD: ") + what + " has " + std::to_string(p.size()) +
                                             " values for " + std::to_string(s.size()) + " sieves");
}

// A grading as points (log10 d, F in 0..1), with the lower bound d_lo
// prepended at F = 0 when it lies below the smallest sieve.
struct Curve {
  std::vector<double> x, f;
  double at(double xq) const {
    if (xq <= x.front()) return f.front();
    if (xq >= x.back()) return f.back();
    const size_t k = static_cast<size_t>(std::upper_bound(x.begin(), x.end(), xq) - x.begin());
    const double t = (xq - x[k - 1]) / (x[k] - x[k - 1]);
    return f[k - 1] + t * (f[k] - f[k - 1]);
  }
};

Curve make_curve(std::span<const double> s, std::span<const double> p, double d_lo) {
  Curve c;
  if (d_lo > 0 && d_lo < s.front()) {
    c.x.push_back(std::log10(d_lo));
    c.f.push_back(0.0);
  }
  for (size_t k = 0; k < s.size(); ++k) {
    c.x.push_back(std::log10(s[k]));
    c.f.push_back(p[k] / 100.0);
  }
  return c;
}

// Integral of a piecewise-linear curve (in x) from a to b, exact.
double integrate(const Curve& c, double a, double b) {
  std::vector<double> xs{a, b};
  for (double x : c.x)
    if (x > a && x < b) xs.push_back(x);
  std::sort(xs.begin(), xs.end());
  double sum = 0;
  for (size_t k = 1; k < xs.size(); ++k) sum += 0.5 * (c.at(xs[k - 1]) + c.at(xs[k])) * (xs[k] - xs[k - 1]);
  return sum;
}

}  // namespace

std::vector<double> percent_passing(std::span<const double> sizes, std::span<const double> masses,
                                    std::span<const double> sieves) {
  check_sieves(sieves);
  if (sizes.size() != masses.size()) throw UsageError("PSD: sizes and masses differ in length");
  double total = 0;
  for (double m : masses) {
    if (!(m >= 0) || !std::isfinite(m)) throw InputError("PSD: a particle mass is negative or not finite");
    total += m;
  }
  if (!(total > 0)) throw InputError("PSD: total particle mass is zero");
  std::vector<double> pass(sieves.size(), 0.0);
  for (size_t n = 0; n < sizes.size(); ++n) {
    // First sieve the particle passes (size <= sieve).
    const size_t k = static_cast<size_t>(std::lower_bound(sieves.begin(), sieves.end(), sizes[n]) - sieves.begin());
    if (k < pass.size()) pass[k] += masses[n];
  }
  double run = 0;
  for (auto& v : pass) {
    run += v;
    v = 100.0 * run / total;
  }
  return pass;
}

double grading_quantile(std::span<const double> s, std::span<const double> p, double q) {
  check_sieves(s);
  check_curve(s, p, "curve");
  for (size_t k = 0; k < s.size(); ++k) {
    if (p[k] < q) continue;
    if (k == 0) return p[0] == q ? s[0] : kNaN;
    if (p[k] == p[k - 1]) return s[k - 1];
    const double t = (q - p[k - 1]) / (p[k] - p[k - 1]);
    return s[k - 1] * std::pow(s[k] / s[k - 1], t);
  }
  return kNaN;
}

std::vector<double> class_percent(std::span<const double> values, std::span<const double> t) {
  for (size_t k = 1; k < t.size(); ++k)
    if (!(t[k] > t[k - 1])) throw UsageError("class thresholds must be strictly ascending");
  std::vector<double> out(t.size() + 1, 0.0);
  if (values.empty()) return out;
  for (double v : values) out[static_cast<size_t>(std::upper_bound(t.begin(), t.end(), v) - t.begin())] += 1;
  for (auto& o : out) o *= 100.0 / static_cast<double>(values.size());
  return out;
}

double hardin_potential(std::span<const double> s, std::span<const double> p, double cutoff) {
  check_sieves(s);
  check_curve(s, p, "grading");
  if (!(cutoff > 0) || cutoff > s.back()) throw UsageError("Hardin cut-off must be in (0, largest sieve]");
  const Curve c = make_curve(s, p, cutoff);
  const double a = std::log10(cutoff), b = std::log10(s.back());
  return (b - a) - integrate(c, a, b);
}

double hardin_br(std::span<const double> s, std::span<const double> initial, std::span<const double> current,
                 double cutoff) {
  const double b0 = hardin_potential(s, initial, cutoff);
  if (!(b0 > 0)) return kNaN;
  return (b0 - hardin_potential(s, current, cutoff)) / b0;
}

double einav_br(std::span<const double> s, std::span<const double> initial, std::span<const double> current,
                const EinavOptions& opt) {
  check_sieves(s);
  check_curve(s, initial, "initial grading");
  check_curve(s, current, "current grading");
  const double dm = opt.d_min > 0 ? opt.d_min : s.front();
  size_t kM = 0;  // first sieve passing 100 % of the initial grading
  while (kM < s.size() && initial[kM] < 100.0 - 1e-9) ++kM;
  if (kM == s.size()) throw InputError("Einav Br*: the initial grading never reaches 100 % passing");
  const double dM = s[kM];
  if (!(dm < dM)) throw UsageError("Einav Br*: d_min must be below the initial grading's largest size");
  const double e = 3.0 - opt.fractal_dimension;
  if (!(e > 0)) throw UsageError("Einav Br*: fractal dimension must be < 3");
  const Curve c0 = make_curve(s, initial, dm), c1 = make_curve(s, current, dm);
  const double a = std::log10(dm), b = std::log10(dM);
  const double lo = std::pow(dm, e), hi = std::pow(dM, e);
  auto fu = [&](double x) { return std::clamp((std::pow(10.0, x * e) - lo) / (hi - lo), 0.0, 1.0); };
  // Simpson on 64 steps per decade-fraction between a and b (Fu is smooth).
  const int n = 64 * std::max<int>(1, static_cast<int>(std::ceil((b - a) * 10)));
  double iu = 0;
  const double hstep = (b - a) / n;
  for (int k = 0; k <= n; ++k) {
    const double w = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
    iu += w * fu(a + k * hstep);
  }
  iu *= hstep / 3.0;
  const double i0 = integrate(c0, a, b), i1 = integrate(c1, a, b);
  const double bp = iu - i0;
  if (!(bp > 0)) return kNaN;
  return (i1 - i0) / bp;
}

}  // namespace tg::measure

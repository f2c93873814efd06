#include "dem/calibration/surrogate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "dem/breakage/strength.hpp"

namespace tg::dem::calibration {
namespace surrogate_detail {

// Draw n of stream `stream` (a purpose: design, candidates, ...) of `seed`:
// the strength draw's counter-based hash (dem/breakage/strength.hpp), so
// every draw is a pure function of its arguments.
double draw(uint64_t seed, uint64_t stream, uint64_t n) {
  return breakage::strength_uniform(seed ^ breakage::detail::mix64(stream + 0x51ca1b), n);
}

double sq_dist(const Point& a, const Point& b) {
  double s = 0;
  for (size_t k = 0; k < a.size(); ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return s;
}

// Grid of the hyperparameters (in the unit box's units): length scales from
// a twentieth of the box to twice it, nuggets from exact to very noisy.
const std::vector<double> kLengthGrid{0.05, 0.08, 0.12, 0.18, 0.27, 0.4, 0.6, 0.9, 1.35, 2.0};
const std::vector<double> kNuggetGrid{1e-6, 1e-4, 1e-3, 1e-2, 0.05, 0.2};

// Smallest distance (unit box) between a proposal and any earlier point.
constexpr double kMinSeparation = 0.01;

double normal_pdf(double z) { return std::exp(-0.5 * z * z) / std::sqrt(2 * std::numbers::pi); }
double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

}  // namespace surrogate_detail

std::vector<Point> latin_hypercube(int n, int d, uint64_t seed, int candidates) {
  using surrogate_detail::draw;
  if (n < 1 || d < 1 || candidates < 1) throw std::invalid_argument("latin_hypercube: n, d, candidates must be >= 1");
  std::vector<Point> best;
  double best_gap = -1;
  uint64_t counter = 0;
  for (int c = 0; c < candidates; ++c) {
    std::vector<Point> x(n, Point(d));
    for (int k = 0; k < d; ++k) {
      std::vector<int> strata(n);
      std::iota(strata.begin(), strata.end(), 0);
      for (int i = n - 1; i > 0; --i) {  // Fisher–Yates
        const int j = std::min(i, static_cast<int>(draw(seed, 1, counter++) * (i + 1)));
        std::swap(strata[i], strata[j]);
      }
      for (int i = 0; i < n; ++i) x[i][k] = (strata[i] + draw(seed, 1, counter++)) / n;
    }
    double gap = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) gap = std::min(gap, surrogate_detail::sq_dist(x[i], x[j]));
    if (gap > best_gap) {
      best_gap = gap;
      best = std::move(x);
    }
  }
  return best;
}

double GaussianProcess::kernel(const Point& a, const Point& b) const {
  double r2 = 0;
  for (size_t k = 0; k < a.size(); ++k) r2 += std::pow((a[k] - b[k]) / ell_[k], 2);
  const double r = std::sqrt(5 * r2);  // √5 r / ℓ
  return (1 + r + r * r / 3) * std::exp(-r);
}

bool GaussianProcess::factor() {
  const int n = static_cast<int>(x_.size());
  Eigen::MatrixXd K(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j <= i; ++j) K(i, j) = K(j, i) = kernel(x_[i], x_[j]) + (i == j ? nugget_ : 0.0);
  llt_.compute(K);
  if (llt_.info() != Eigen::Success) return false;
  alpha_ = llt_.solve(z_);
  // Profile likelihood: the signal variance that maximises it given the rest.
  signal_var_ = std::max(z_.dot(alpha_) / n, 1e-300);
  const Eigen::MatrixXd L = llt_.matrixL();
  double logdet = 0;
  for (int i = 0; i < n; ++i) logdet += 2 * std::log(L(i, i));
  loglik_ = -0.5 * n * std::log(signal_var_) - 0.5 * logdet - 0.5 * n * (1 + std::log(2 * std::numbers::pi));
  return true;
}

void GaussianProcess::refit(const std::vector<Point>& x, const std::vector<double>& y) {
  if (x.empty() || x.size() != y.size()) throw std::invalid_argument("GaussianProcess: need as many values as points");
  x_ = x;
  const int n = static_cast<int>(y.size());
  y_mean_ = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double ss = 0;
  for (double v : y) ss += (v - y_mean_) * (v - y_mean_);
  y_sd_ = n > 1 && ss > 0 ? std::sqrt(ss / (n - 1)) : 1.0;
  z_.resize(n);
  for (int i = 0; i < n; ++i) z_[i] = (y[i] - y_mean_) / y_sd_;
  if (ell_.size() != x_.front().size()) ell_.assign(x_.front().size(), 0.27);
  // A nugget too small for coincident fantasies: raise it until K factors.
  while (!factor()) nugget_ = std::max(nugget_ * 10, 1e-8);
}

void GaussianProcess::fit(const std::vector<Point>& x, const std::vector<double>& y) {
  using namespace surrogate_detail;
  refit(x, y);
  const int d = static_cast<int>(x.front().size());
  // Every combination of per-axis length scales (up to 3 axes; more share one).
  const int axes = d <= 3 ? d : 1;
  int combos = 1;
  for (int k = 0; k < axes; ++k) combos *= static_cast<int>(kLengthGrid.size());
  double best = -std::numeric_limits<double>::infinity();
  std::vector<double> best_ell = ell_;
  double best_nugget = nugget_;
  for (double g : kNuggetGrid)
    for (int c = 0; c < combos; ++c) {
      int code = c;
      for (int k = 0; k < d; ++k) {
        const int G = static_cast<int>(kLengthGrid.size());
        ell_[k] = kLengthGrid[axes == d ? code % G : c];
        if (axes == d) code /= G;
      }
      nugget_ = g;
      if (factor() && loglik_ > best) {
        best = loglik_;
        best_ell = ell_;
        best_nugget = g;
      }
    }
  ell_ = best_ell;
  nugget_ = best_nugget;
  factor();
}

void GaussianProcess::predict(const Point& p, double& mean, double& sd) const {
  const int n = static_cast<int>(x_.size());
  Eigen::VectorXd k(n);
  for (int i = 0; i < n; ++i) k[i] = kernel(p, x_[i]);
  mean = y_mean_ + y_sd_ * k.dot(alpha_);
  const double var = signal_var_ * std::max(0.0, 1.0 - k.dot(llt_.solve(k)));
  sd = y_sd_ * std::sqrt(var);
}

double GaussianProcess::signal_sd() const { return y_sd_ * std::sqrt(signal_var_); }

double expected_improvement(double mean, double sd, double best) {
  using namespace surrogate_detail;
  const double gain = best - mean;
  if (!(sd > 1e-12)) return std::max(gain, 0.0);
  const double z = gain / sd;
  return gain * normal_cdf(z) + sd * normal_pdf(z);
}

Point minimise_on_box(int d, uint64_t seed, const std::function<double(const Point&)>& f) {
  using surrogate_detail::draw;
  // Candidates: 256 per dimension at random, kept by value; the best 4 start
  // a compass search (step halves on failure, down to 1e-4 of the box).
  const int m = 256 * d, keep = 4;
  std::vector<std::pair<double, Point>> cand;
  cand.reserve(m);
  for (int i = 0; i < m; ++i) {
    Point p(d);
    for (int k = 0; k < d; ++k) p[k] = draw(seed, 2, static_cast<uint64_t>(i) * d + k);
    cand.emplace_back(f(p), std::move(p));
  }
  std::partial_sort(cand.begin(), cand.begin() + keep, cand.end(),
                    [](const auto& a, const auto& b) { return a.first < b.first; });
  Point best = cand.front().second;
  double best_v = cand.front().first;
  for (int s = 0; s < keep; ++s) {
    Point p = cand[s].second;
    double v = cand[s].first;
    for (double step = 0.05; step > 1e-4;) {
      bool moved = false;
      for (int k = 0; k < d && !moved; ++k)
        for (double sign : {1.0, -1.0}) {
          Point q = p;
          q[k] = std::clamp(q[k] + sign * step, 0.0, 1.0);
          const double w = f(q);
          if (w < v) {
            p = q;
            v = w;
            moved = true;
            break;
          }
        }
      if (!moved) step /= 2;
    }
    if (v < best_v) {
      best_v = v;
      best = p;
    }
  }
  return best;
}

namespace {

// Non-finite values replaced by the worst finite one (1 when none is).
std::vector<double> worst_for_failed(std::vector<double> y) {
  double worst = -std::numeric_limits<double>::infinity();
  for (double v : y)
    if (std::isfinite(v)) worst = std::max(worst, v);
  if (!std::isfinite(worst)) worst = 1;
  for (double& v : y)
    if (!std::isfinite(v)) v = worst;
  return y;
}

}  // namespace

void Surrogate::fit(const std::vector<Point>& x, const std::vector<Evaluation>& e, const SeparateTerm& term) {
  term_ = term;
  x_ = x;
  xq_.clear();
  yq_.clear();
  auto measured = [&](const Evaluation& v) { return term.active() && std::isfinite(v.quantity) && v.quantity > 0; };
  for (size_t i = 0; i < x.size(); ++i)
    if (measured(e[i])) {
      xq_.push_back(x[i]);
      yq_.push_back(std::log(e[i].quantity));
    }
  // Two measured q at least, or one GP of the whole value.
  composite_ = xq_.size() >= 2;
  // The rest (a failed run, or one whose q is missing: NaN, then the worst rest).
  y_.clear();
  for (const Evaluation& v : e)
    y_.push_back(!composite_ ? v.value
                 : measured(v) ? v.value - term.weight * std::abs(v.quantity - term.target) / term.target
                               : std::numeric_limits<double>::quiet_NaN());
  y_ = worst_for_failed(y_);
  rest_.fit(x_, y_);
  if (composite_) log_q_.fit(xq_, yq_);
}

double Surrogate::guess(const Point& p) const {
  double mu, sd;
  rest_.predict(p, mu, sd);
  if (!composite_) return mu;
  double m, s;
  log_q_.predict(p, m, s);
  return mu + term_.weight * std::abs(std::exp(m) - term_.target) / term_.target;
}

void Surrogate::predict(const Point& p, double& mean, double& sd) const {
  using namespace surrogate_detail;
  rest_.predict(p, mean, sd);
  if (!composite_) return;
  double m, s;
  log_q_.predict(p, m, s);
  // term = weight |q - target| / target with q ~ N(e^m, (e^m s)^2): a
  // folded normal of mu_t = weight (e^m - target) / target, sd s_t.
  const double mu_t = term_.weight * (std::exp(m) - term_.target) / term_.target;
  const double s_t = term_.weight * std::exp(m) * s / term_.target;
  double e = std::abs(mu_t), var = 0;
  if (s_t > 1e-12) {
    const double z = mu_t / s_t;
    e = s_t * std::sqrt(2 / std::numbers::pi) * std::exp(-0.5 * z * z) + mu_t * (1 - 2 * normal_cdf(-z));
    var = std::max(0.0, mu_t * mu_t + s_t * s_t - e * e);
  }
  mean += e;
  sd = std::sqrt(sd * sd + var);
}

double Surrogate::believe(const Point& p) {
  double mu, sd;
  rest_.predict(p, mu, sd);
  const double g = guess(p);
  x_.push_back(p);
  y_.push_back(mu);
  rest_.refit(x_, y_);
  if (composite_) {
    double m, s;
    log_q_.predict(p, m, s);
    xq_.push_back(p);
    yq_.push_back(m);
    log_q_.refit(xq_, yq_);
  }
  return g;
}

SearchResult minimise(int d, const SearchOptions& o, const Evaluate& evaluate) {
  SearchOptions plain = o;
  plain.separate = {};
  return minimise(d, plain, [&](const std::vector<Point>& pts) {
    std::vector<Evaluation> e;
    for (double v : evaluate(pts)) e.push_back({v, std::numeric_limits<double>::quiet_NaN()});
    return e;
  });
}

SearchResult minimise(int d, const SearchOptions& o, const EvaluateTerms& evaluate) {
  using surrogate_detail::kMinSeparation;
  if (d < 1 || o.initial < 2 || o.evaluations < o.initial || o.batch < 1)
    throw std::invalid_argument("minimise: need d >= 1, 2 <= initial <= evaluations, batch >= 1");
  if (o.separate.active() && !(std::isfinite(o.separate.target) && std::isfinite(o.separate.weight)))
    throw std::invalid_argument("minimise: the separate term's target and weight must be finite");
  SearchResult r;
  auto evaluations = [&] {
    std::vector<Evaluation> e;
    for (size_t i = 0; i < r.values.size(); ++i) e.push_back({r.values[i], r.quantities[i]});
    return e;
  };
  auto run = [&](const std::vector<Point>& pts) {
    const std::vector<Evaluation> v = evaluate(pts);
    if (v.size() != pts.size()) throw std::logic_error("minimise: evaluate returned the wrong number of values");
    for (size_t i = 0; i < pts.size(); ++i) {
      r.points.push_back(pts[i]);
      r.values.push_back(v[i].value);
      r.quantities.push_back(v[i].quantity);
    }
  };
  run(latin_hypercube(o.initial, d, o.seed));
  int round = 0;
  while (static_cast<int>(r.points.size()) < o.evaluations) {
    const int q = std::min(o.batch, o.evaluations - static_cast<int>(r.points.size()));
    std::vector<Point> x = r.points;
    // Failed evaluations count as the worst value seen.
    std::vector<double> y = worst_for_failed(r.values);
    Surrogate model;
    model.fit(x, evaluations(), o.separate);
    std::vector<Point> picks;
    for (int j = 0; j < q; ++j) {
      const double best = *std::min_element(y.begin(), y.end());
      const Point p = minimise_on_box(d, o.seed + 1000003ULL * (++round), [&](const Point& u) {
        // No point within 1 % of the box of one already run or picked: with a
        // nugget the GP keeps some EI there (seen: a batch's two runs at the
        // same corner), and a repeated run of a deterministic DEM teaches nothing.
        for (const Point& v : x)
          if (surrogate_detail::sq_dist(u, v) < kMinSeparation * kMinSeparation) return 0.0;
        double mu, sd;
        model.predict(u, mu, sd);
        return -expected_improvement(mu, sd, best);
      });
      picks.push_back(p);
      x.push_back(p);  // kriging believer: the model's guess stands in for the run
      y.push_back(model.believe(p));
    }
    run(picks);
  }
  for (size_t i = 0; i < r.values.size(); ++i)
    if (std::isfinite(r.values[i]) && (r.best < 0 || r.values[i] < r.values[r.best])) r.best = static_cast<int>(i);
  r.surrogate.fit(r.points, evaluations(), o.separate);
  r.predicted_optimum = minimise_on_box(d, o.seed + 7, [&](const Point& u) { return r.surrogate.guess(u); });
  r.surrogate.predict(r.predicted_optimum, r.predicted_value, r.predicted_sd);
  r.predicted_value = r.surrogate.guess(r.predicted_optimum);
  return r;
}

}  // namespace tg::dem::calibration

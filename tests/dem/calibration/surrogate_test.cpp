// The calibration's search (dem/calibration/surrogate.hpp) on functions whose
// minimum is known analytically; the GP against hand-checkable properties.
#include "dem/calibration/surrogate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cal = tg::dem::calibration;

TEST(Calibration, LatinHypercubeOnePointPerStratum) {
  const int n = 12, d = 3;
  const auto x = cal::latin_hypercube(n, d, 5);
  ASSERT_EQ(x.size(), static_cast<size_t>(n));
  for (int k = 0; k < d; ++k) {
    std::vector<int> count(n, 0);
    for (const auto& p : x) {
      ASSERT_GE(p[k], 0.0);
      ASSERT_LT(p[k], 1.0);
      ++count[static_cast<int>(p[k] * n)];
    }
    for (int c : count) EXPECT_EQ(c, 1) << "axis " << k;
  }
  // Same seed, same design; another seed, another design.
  EXPECT_EQ(cal::latin_hypercube(n, d, 5), x);
  EXPECT_NE(cal::latin_hypercube(n, d, 6), x);
}

TEST(Calibration, LatinHypercubeMaximinSpreadsPoints) {
  // The maximin choice among 64 designs has a closest pair no closer than a
  // single design's (here: strictly farther for this seed).
  auto gap = [](const std::vector<cal::Point>& x) {
    double g = 1e9;
    for (size_t i = 0; i < x.size(); ++i)
      for (size_t j = i + 1; j < x.size(); ++j) g = std::min(g, std::hypot(x[i][0] - x[j][0], x[i][1] - x[j][1]));
    return g;
  };
  EXPECT_GT(gap(cal::latin_hypercube(10, 2, 3, 64)), gap(cal::latin_hypercube(10, 2, 3, 1)));
}

TEST(Calibration, GaussianProcessInterpolatesSmoothData) {
  // Noise-free samples of a smooth function: the posterior mean passes
  // through them and predicts a midpoint well, and its sd is ~0 at the data.
  std::vector<cal::Point> x;
  std::vector<double> y;
  auto f = [](const cal::Point& p) { return std::sin(3 * p[0]) + p[1] * p[1]; };
  for (const auto& p : cal::latin_hypercube(25, 2, 11)) {
    x.push_back(p);
    y.push_back(f(p));
  }
  cal::GaussianProcess gp;
  gp.fit(x, y);
  double mu, sd;
  gp.predict(x[3], mu, sd);
  EXPECT_NEAR(mu, y[3], 1e-2);
  EXPECT_LT(sd, 0.05);
  gp.predict({0.5, 0.5}, mu, sd);
  EXPECT_NEAR(mu, f({0.5, 0.5}), 0.02);
  // Far outside the data's reach the sd returns to the signal's.
  cal::GaussianProcess one;
  one.fit({{0.0, 0.0}, {0.05, 0.0}, {0.0, 0.05}}, {1.0, 2.0, 3.0});
  one.predict({1.0, 1.0}, mu, sd);
  EXPECT_NEAR(sd, one.signal_sd(), 0.05 * one.signal_sd());
}

TEST(Calibration, ExpectedImprovementClosedForm) {
  // sd = 0: the plain improvement; mean = best: sd * phi(0) = sd / sqrt(2 pi).
  EXPECT_DOUBLE_EQ(cal::expected_improvement(1.0, 0.0, 3.0), 2.0);
  EXPECT_DOUBLE_EQ(cal::expected_improvement(4.0, 0.0, 3.0), 0.0);
  EXPECT_NEAR(cal::expected_improvement(3.0, 2.0, 3.0), 2.0 / std::sqrt(2 * std::numbers::pi), 1e-12);
  // best - mean = sd: sd (Phi(1) + phi(1)) = 0.8413447 + 0.2419707.
  EXPECT_NEAR(cal::expected_improvement(2.0, 1.0, 3.0), 1.0833154, 1e-6);
}

TEST(Calibration, FindsTheMinimumOfAQuadratic) {
  // Minimum 0 at (0.3, 0.7); 8 design points + 8 EI steps.
  cal::SearchOptions o;
  o.evaluations = 16;
  o.initial = 8;
  o.seed = 3;
  const auto r = cal::minimise(2, o, [](const std::vector<cal::Point>& pts) {
    std::vector<double> v;
    for (const auto& p : pts) v.push_back(std::pow(p[0] - 0.3, 2) + 2 * std::pow(p[1] - 0.7, 2));
    return v;
  });
  ASSERT_EQ(r.values.size(), 16u);
  EXPECT_NEAR(r.points[r.best][0], 0.3, 0.01);  // measured 0.003
  EXPECT_NEAR(r.points[r.best][1], 0.7, 0.01);
  EXPECT_NEAR(r.predicted_optimum[0], 0.3, 0.01);
  EXPECT_NEAR(r.predicted_optimum[1], 0.7, 0.01);
}

// Branin on [-5, 10] x [0, 15]: three global minima of 0.397887 at (-pi,
// 12.275), (pi, 2.275), (9.42478, 2.475).
namespace {
double branin(const cal::Point& u) {
  const double x = -5 + 15 * u[0], y = 15 * u[1], pi = std::numbers::pi;
  const double b = 5.1 / (4 * pi * pi), c = 5 / pi, t = 1 / (8 * pi);
  return std::pow(y - b * x * x + c * x - 6, 2) + 10 * (1 - t) * std::cos(x) + 10;
}
}  // namespace

TEST(Calibration, FindsAGlobalMinimumOfBranin) {
  for (int batch : {1, 3}) {
    cal::SearchOptions o;
    o.evaluations = 30;
    o.initial = 10;
    o.batch = batch;
    o.seed = 1;
    const auto r = cal::minimise(2, o, [](const std::vector<cal::Point>& pts) {
      std::vector<double> v;
      for (const auto& p : pts) v.push_back(branin(p));
      return v;
    });
    // Measured 0.005 (batch 1) and 0.004 (batch 3) above the minimum; the
    // best of a 30-point Latin hypercube alone is 1.28 above it (median over
    // 200 scipy.stats.qmc designs; 1 % of them come within 0.02).
    EXPECT_LT(r.values[r.best] - 0.397887, 0.02) << "batch " << batch;
  }
}

TEST(Calibration, FailedEvaluationsAreAvoided) {
  // The right half "fails" (NaN): the search still finds the left minimum.
  cal::SearchOptions o;
  o.evaluations = 16;
  o.initial = 8;
  const auto r = cal::minimise(2, o, [](const std::vector<cal::Point>& pts) {
    std::vector<double> v;
    for (const auto& p : pts)
      v.push_back(p[0] > 0.6 ? std::nan("") : std::pow(p[0] - 0.2, 2) + std::pow(p[1] - 0.5, 2));
    return v;
  });
  ASSERT_GE(r.best, 0);
  EXPECT_TRUE(std::isfinite(r.values[r.best]));
  EXPECT_NEAR(r.points[r.best][0], 0.2, 0.02);
  EXPECT_NEAR(r.points[r.best][1], 0.5, 0.02);
}

// A stand-in for dem calibrate's objective with a crush term: a rest that
// sees u0 well and u1 hardly, with a deterministic ragged floor (the DEM's
// chaos), plus w |q - c| / c where q is smooth, rises along u1 and falls
// along u0 (as the crush tests' bonds broken with λ and σ_t0). The
// minimum of the whole lies where the term's narrow valley crosses the
// rest's: near u* = (0.35, 0.3).
namespace {
constexpr double kU0 = 0.35, kU1 = 0.3, kWeight = 1;
double stand_in_q(const cal::Point& u) { return 80 * std::exp(0.6 * u[1] - 0.3 * u[0]); }
double stand_in_rest(const cal::Point& u) {
  return 0.1 + 0.8 * std::pow(u[0] - kU0, 2) + 0.05 * std::pow(u[1] - 0.6, 2) + 0.03 * std::sin(41 * u[0] + 57 * u[1]);
}
std::vector<cal::Evaluation> stand_in(const std::vector<cal::Point>& pts) {
  const double c = stand_in_q({kU0, kU1});
  std::vector<cal::Evaluation> e;
  for (const auto& p : pts) {
    const double q = stand_in_q(p);
    e.push_back({stand_in_rest(p) + kWeight * std::abs(q - c) / c, q});
  }
  return e;
}
}  // namespace

TEST(Calibration, ATermModelledApartPutsTheOptimumInItsValley) {
  cal::SearchOptions o;
  o.evaluations = 20;
  o.initial = 10;
  o.batch = 2;
  o.seed = 4;
  o.separate = {stand_in_q({kU0, kU1}), kWeight};
  const auto r = cal::minimise(2, o, stand_in);
  ASSERT_TRUE(r.surrogate.composite());
  // On the term's valley: q at the optimum within 2 % of the target (the
  // plug-in guess puts it there by construction; measured 1.000).
  const double c = stand_in_q({kU0, kU1});
  EXPECT_NEAR(stand_in_q(r.predicted_optimum) / c, 1.0, 0.02);
  // Along the valley the rest's GP decides, through its ragged floor:
  // measured (0.410, 0.330). Over design seeds 1-12 the optimum lay 0.008-0.126
  // from u* (median 0.041; one GP of the whole value: 0.005-0.103, median
  // 0.045) and the best run 0.017-0.087 (median 0.028; whole: 0.031-0.101,
  // median 0.062); the DEM's recovery is the test that matters
  // (bench/dem/RESULTS.md, "A separate model of the crush term").
  EXPECT_NEAR(r.predicted_optimum[0], kU0, 0.1);
  EXPECT_NEAR(r.predicted_optimum[1], kU1, 0.05);
  // The quantities are returned as measured.
  ASSERT_EQ(r.quantities.size(), r.points.size());
  EXPECT_DOUBLE_EQ(r.quantities[3], stand_in_q(r.points[3]));
  // Without the separate term the same evaluations give one GP.
  cal::SearchOptions plain = o;
  plain.separate = {};
  EXPECT_FALSE(cal::minimise(2, plain, stand_in).surrogate.composite());
}

TEST(Calibration, CompositePredictionIsTheFoldedNormalOfItsTerm) {
  // Against a numerical integral over q ~ N(e^m, (e^m s)^2), the two GPs'
  // own predictions taken as given.
  const auto x = cal::latin_hypercube(12, 2, 9);
  const cal::SeparateTerm term{stand_in_q({kU0, kU1}), kWeight};
  cal::Surrogate s;
  s.fit(x, stand_in(x), term);
  ASSERT_TRUE(s.composite());
  for (const cal::Point& p : {cal::Point{0.5, 0.5}, cal::Point{0.35, 0.3}, cal::Point{0.9, 0.05}}) {
    double mu, sd, m, sq;
    s.rest().predict(p, mu, sd);
    s.log_q().predict(p, m, sq);
    double e1 = 0, e2 = 0, w = 0;
    for (int i = -4000; i <= 4000; ++i) {
      const double z = i / 500.0, pz = std::exp(-0.5 * z * z);
      const double t = term.weight * std::abs(std::exp(m) * (1 + sq * z) - term.target) / term.target;
      e1 += pz * t;
      e2 += pz * t * t;
      w += pz;
    }
    e1 /= w;
    e2 /= w;
    double mean, sdev;
    s.predict(p, mean, sdev);
    EXPECT_NEAR(mean, mu + e1, 1e-6);
    EXPECT_NEAR(sdev, std::sqrt(sd * sd + e2 - e1 * e1), 1e-6);
    EXPECT_DOUBLE_EQ(s.guess(p), mu + term.weight * std::abs(std::exp(m) - term.target) / term.target);
  }
  // The rest's GP follows the value less the term (within the ragged
  // floor's 0.03, which its nugget may smooth), not the value.
  for (size_t i = 0; i < x.size(); ++i) {
    double mu, sd;
    s.rest().predict(x[i], mu, sd);
    EXPECT_NEAR(mu, stand_in_rest(x[i]), 0.035) << "point " << i;
  }
}

TEST(Calibration, ATermWithoutTwoMeasuredQuantitiesFallsBackToOneModel) {
  const auto x = cal::latin_hypercube(8, 2, 3);
  std::vector<cal::Evaluation> e = stand_in(x);
  for (size_t i = 1; i < e.size(); ++i) e[i].quantity = std::nan("");
  cal::Surrogate s;
  s.fit(x, e, {stand_in_q({kU0, kU1}), 1});
  EXPECT_FALSE(s.composite());
  double mu, sd;
  s.predict(x[2], mu, sd);
  EXPECT_NEAR(mu, e[2].value, 0.05);  // the whole value's GP
}

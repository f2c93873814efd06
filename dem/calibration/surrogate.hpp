// Few-run minimisation of an expensive function on the unit box [0,1]^d:
// a seeded space-filling Latin hypercube, then a Gaussian-process surrogate
// whose expected improvement picks the next points (Jones, Schonlau & Welch
// 1998, "Efficient global optimization of expensive black-box functions",
// doi:10.1023/A:1008306431147). Used by `tomograin dem calibrate`
// (dem/calibration/calibrate.hpp), where one evaluation is one DEM run.
//
// Surrogate: zero-mean GP on the standardised objective, Matérn 5/2 kernel
// with one length scale per dimension (ARD), a nugget for noisy runs; the
// length scales and nugget are chosen on a grid by the profile marginal
// likelihood (the signal variance has a closed form given the others).
// Batches of q points (parallel runs) are picked by the "kriging believer":
// each picked point is added with its predicted mean as if observed, and the
// next one maximises EI on that fantasy (hyperparameters kept).
// Everything is deterministic given the seed (no thread-dependent sums).
#pragma once
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include <Eigen/Dense>

namespace tg::dem::calibration {

using Point = std::vector<double>;  // in [0,1]^d

// n points in [0,1]^d, one in each of the n strata of every axis (a Latin
// hypercube), each placed uniformly inside its cell; of `candidates` such
// designs drawn from `seed`, the one whose closest pair is farthest apart
// (maximin). Deterministic given the arguments.
std::vector<Point> latin_hypercube(int n, int d, uint64_t seed, int candidates = 64);

class GaussianProcess {
 public:
  // Fits to (x, y), choosing hyperparameters by marginal likelihood. y finite.
  void fit(const std::vector<Point>& x, const std::vector<double>& y);
  // Same hyperparameters, new data (the kriging believer's fantasies).
  void refit(const std::vector<Point>& x, const std::vector<double>& y);
  // Posterior mean and standard deviation of the latent function at p (in y's units).
  void predict(const Point& p, double& mean, double& sd) const;

  const std::vector<double>& length_scales() const { return ell_; }
  double nugget() const { return nugget_; }  // noise variance / signal variance
  double signal_sd() const;                  // in y's units
  double log_likelihood() const { return loglik_; }

 private:
  double kernel(const Point& a, const Point& b) const;  // unit amplitude
  bool factor();  // Cholesky of K + nugget I; false when not positive definite

  std::vector<Point> x_;
  Eigen::VectorXd alpha_;  // (K + g I)^-1 z, z = standardised y
  Eigen::LLT<Eigen::MatrixXd> llt_;
  Eigen::VectorXd z_;
  double y_mean_ = 0, y_sd_ = 1, signal_var_ = 1, nugget_ = 1e-6, loglik_ = 0;
  std::vector<double> ell_;
};

// Expected improvement below `best` (minimisation) of a normal prediction.
double expected_improvement(double mean, double sd, double best);

// One term of the objective modelled on its own (a composite objective:
// Astudillo & Frazier 2019, "Bayesian optimization of composite functions",
// ICML): value = rest + weight |q - target| / target, where q > 0 is a
// quantity each evaluation measures (dem calibrate: the crush tests' mean
// bonds broken). q is smooth in the parameters and its noise small; the
// term's kink at q = target is neither, and one GP of the whole value
// rounds that narrow valley off: where it lies along a parameter the rest
// hardly sees (λ), the whole-value optimum landed 11 % from a known λ that
// the composite put 3.3 % from it from the same runs (bench/dem/RESULTS.md,
// "A separate model of the crush term"). So log q gets a GP of its own and
// rest another.
struct SeparateTerm {
  double target = 0;  // 0: none (one GP of the value)
  double weight = 0;
  bool active() const { return target > 0 && weight > 0; }
};

struct SearchOptions {
  int evaluations = 20;  // total, the initial design included
  int initial = 8;       // Latin hypercube points evaluated first
  int batch = 1;         // points proposed per round after the initial design
  uint64_t seed = 1;
  SeparateTerm separate;  // a term modelled apart (Evaluation::quantity)
};

struct Evaluation {
  double value = std::numeric_limits<double>::quiet_NaN();     // NaN: the evaluation failed
  double quantity = std::numeric_limits<double>::quiet_NaN();  // q of SearchOptions::separate
};

// One round of evaluations: objectives for the points (NaN = the evaluation
// failed; it is then counted as the worst value seen, so the search avoids it).
using Evaluate = std::function<std::vector<double>(const std::vector<Point>& points)>;
using EvaluateTerms = std::function<std::vector<Evaluation>(const std::vector<Point>& points)>;

// What the search believes about the objective: a GP of it, or, with a
// separate term, a GP of the rest (value minus the term) and one of log q.
class Surrogate {
 public:
  // Fits to the evaluations (failed ones: the rest at its worst value
  // seen, q left out); hyperparameters by marginal likelihood.
  void fit(const std::vector<Point>& x, const std::vector<Evaluation>& e, const SeparateTerm& term);
  // Adds p as if evaluated at the model's own guess (the kriging believer),
  // hyperparameters kept; returns that guess.
  double believe(const Point& p);
  // Mean and sd of the objective at p. With a separate term q is taken as
  // normal, e^m (1 ± s) for log q ~ (m, s), so the term is a folded normal.
  void predict(const Point& p, double& mean, double& sd) const;
  // The model's best guess of the objective at p: the rest's mean plus the
  // term at q = e^m (the composite's plug-in; minimised for the optimum).
  double guess(const Point& p) const;
  bool composite() const { return composite_; }
  const GaussianProcess& rest() const { return rest_; }    // the whole value's GP without a separate term
  const GaussianProcess& log_q() const { return log_q_; }  // fitted when composite()

 private:
  GaussianProcess rest_, log_q_;
  std::vector<Point> x_, xq_;
  std::vector<double> y_, yq_;
  SeparateTerm term_;
  bool composite_ = false;
};

struct SearchResult {
  std::vector<Point> points;
  std::vector<double> values;      // as returned (NaN kept)
  std::vector<double> quantities;  // Evaluation::quantity, as returned
  int best = -1;                   // index of the lowest finite value
  Surrogate surrogate;             // fitted to every evaluation
  Point predicted_optimum;         // minimum of the surrogate's guess
  double predicted_value = 0, predicted_sd = 0;
};

// Latin hypercube (options.initial points) then EI rounds of options.batch
// until options.evaluations. `evaluate` sees the points in order; values of
// later rounds depend only on earlier values, so results are independent of
// how a round is run (in parallel or not).
SearchResult minimise(int d, const SearchOptions& options, const EvaluateTerms& evaluate);
SearchResult minimise(int d, const SearchOptions& options, const Evaluate& evaluate);  // no separate term

// Minimum over [0,1]^d of f: seeded random candidates, then a compass search
// from the best few. Used for EI (negated) and the surrogate's mean.
Point minimise_on_box(int d, uint64_t seed, const std::function<double(const Point&)>& f);

}  // namespace tg::dem::calibration

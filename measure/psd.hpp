// Particle size distributions (PSD) by mass, their quantiles, shape-class
// histograms and two breakage indices.
//
// Grading: percent passing at sieve size s = 100 * (mass of particles with
// size <= s) / (total mass); mass = volume (uniform density). Between sieves
// the curve is linear in log(size) (the usual semi-log grading plot), which
// is how D10, D50, D60 are read off: D_p = s_k (s_{k+1}/s_k)^t with
// t = (p - P_k) / (P_{k+1} - P_k). Cu = D60 / D10. Quantiles outside the
// sieve range are NaN (a grading finer than the finest sieve says nothing
// about where that mass sits).
//
// Hardin's relative breakage (Hardin 1985, J. Geotech. Eng. 111(10):1177,
// doi:10.1061/(ASCE)0733-9410(1985)111:10(1177)): the breakage potential of
// a grading is the area between the cut-off size (0.074 mm, the No. 200
// sieve) and the curve on a log10(size) axis,
//     Bp = integral_{log10 d_cut}^{log10 s_max} (1 - F(d)) dlog10(d),
// and Br = (Bp_initial - Bp_current) / Bp_initial.
// Einav's relative breakage (Einav 2007, J. Mech. Phys. Solids 55(6):1274,
// doi:10.1016/j.jmps.2006.11.003) measures progress towards an ultimate
// fractal grading instead of the cut-off line:
//     Br* = integral (F - F0) dlog d / integral (Fu - F0) dlog d over [dm, dM],
//     Fu(d) = (d^(3-a) - dm^(3-a)) / (dM^(3-a) - dm^(3-a)),
// with fractal dimension a (2.6 by default, Coop et al. 2004's ultimate
// grading of crushed sands), dM the initial grading's largest size (its first
// sieve passing 100 %) and dm the smallest size considered. F is piecewise
// linear in log d between sieves; below the smallest sieve (down to d_cut or
// dm) it is interpolated linearly in log d from 0 at that lower bound (fines
// assumed spread evenly in log size). The integrals of F are exact for that
// curve; Fu is integrated by Simpson's rule on 64 sub-steps per interval.
// The largest sieve must pass 100 % (measure/grading.hpp's sieves_covering
// extends a sieve set so that it does). The grading of whole stages (which
// particles count, D-values from the sorted table, the default sieves) is
// measure/grading.hpp.
#pragma once
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace tg::measure {

// A figure that is undefined (an empty distribution, a diameter outside the sieves).
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Percent passing (0..100) at each sieve (ascending, > 0). sizes and masses
// have one entry per particle; masses >= 0 with a positive total.
std::vector<double> percent_passing(std::span<const double> sizes, std::span<const double> masses,
                                    std::span<const double> sieves);

// Size at which the sieve curve reaches p percent (log-linear), NaN outside.
// (The stages' D-values come from the sorted table: measure/grading.hpp.)
double grading_quantile(std::span<const double> sieves, std::span<const double> passing, double p);

struct GradingSummary {
  double d10 = 0, d50 = 0, d60 = 0, cu = 0;  // mm; cu = d60 / d10
};

// Percent of values in each class [t_{k-1}, t_k), t_0 = -inf, t_last = +inf:
// thresholds.size() + 1 classes.
std::vector<double> class_percent(std::span<const double> values, std::span<const double> thresholds);
// The reference study's classes (its Figs. 13, 14).
inline std::vector<double> fr_thresholds() { return {0.4, 0.8, 0.9}; }
inline std::vector<double> ar_thresholds() { return {2.0, 3.0}; }

// Hardin's breakage potential (same units as log10 of the sizes: dimensionless).
double hardin_potential(std::span<const double> sieves, std::span<const double> passing, double cutoff = 0.074);
double hardin_br(std::span<const double> sieves, std::span<const double> initial, std::span<const double> current,
                 double cutoff = 0.074);

struct EinavOptions {
  double fractal_dimension = 2.6;
  double d_min = 0;  // <= 0: the smallest sieve
};
double einav_br(std::span<const double> sieves, std::span<const double> initial, std::span<const double> current,
                const EinavOptions& opt = {});

}  // namespace tg::measure

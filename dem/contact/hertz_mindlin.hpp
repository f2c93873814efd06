// Hertz–Mindlin contact between elastic spheres (and sphere–rigid wall), with
// tangential displacement history and a Coulomb cap, as a small value type.
//
// Normal (Hertz 1882):      Fn = 4/3 E* sqrt(R*) δ^{3/2},  tangent stiffness
//                           kn = dFn/dδ = 2 E* sqrt(R* δ),  stored energy
//                           U  = 8/15 E* sqrt(R*) δ^{5/2}.
// Tangential (Mindlin 1949, no-slip stiffness, as in PFC "hertz" and
// LIGGGHTS "tangential history"): kt = 8 G* sqrt(R* δ); the tangential
// displacement ξ is accumulated from the relative tangential velocity of the
// contact points (ξ += vt dt), rotated each step into the current tangent
// plane (its normal component removed, length kept); Ft = -kt ξ. Coulomb:
// |Ft| <= μ Fn, and when capped ξ is shrunk so that -kt ξ equals the capped
// force (the LAMMPS gran/hertz/history convention), so unloading is elastic.
// Effective moduli: 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2, 1/G* = (2-ν1)/G1 + (2-ν2)/G2,
// 1/R* = 1/R1 + 1/R2 (R* = R for a flat wall), m* = m1 m2/(m1+m2) (m for a wall).
// A wall is treated as a body of the grains' own material (as LIGGGHTS does
// with a wall of the same atom type), so sphere-wall E* equals sphere-sphere E*.
//
// Damping (optional, recorded in the run): viscous dashpots in the normal and
// tangential directions with the coefficient of Tsuji et al. (1992,
// doi:10.1016/0032-5910(92)88030-L) in the form LIGGGHTS uses,
//   c = 2 sqrt(5/6) |β| sqrt(S m*),  β = ln e / sqrt(ln² e + π²),
// with S = kn (normal) or kt (tangential); e = 1 turns damping off. The total
// normal force is clamped at zero (no cohesion). Local non-viscous damping
// (PFC) acts on whole particles and lives in the engine, not here.
//
// Cost: O(1) per contact, one sqrt for the stiffness. Validation happens once
// in make_hertz_mindlin(); force() assumes δ > 0 and valid parameters.
#pragma once
#include <cmath>
#include <numbers>
#include <utility>

#include "dem/lanes.hpp"
#include "dem/vec3.hpp"

namespace tg::dem {

struct Material {
  double shear_modulus_Pa = 2.2e9;  // G, reference study Table 1
  double poisson_ratio = 0.25;      // ν, Table 1
  double density_kg_m3 = 2180;      // ρ, Table 1
  double youngs_modulus() const { return 2 * shear_modulus_Pa * (1 + poisson_ratio); }
};

// Parameters of one contact family (sphere–sphere, or sphere–a given wall).
struct HertzMindlin {
  double e_star = 0;     // effective Young's modulus E*, Pa
  double g_star = 0;     // effective shear modulus G*, Pa
  double friction = 0;   // Coulomb μ
  double damp_beta = 0;  // |β| of the restitution coefficient (0 = no viscous damping)
  // ct / cn = sqrt(kt / kn) = sqrt(4 G* / E*): the tangential dashpot from
  // the normal one without a second square root per contact.
  double damp_t_over_n = 0;

  double normal_force(double delta, double r_eff) const {
    return 4.0 / 3.0 * e_star * std::sqrt(r_eff) * delta * std::sqrt(delta);
  }
  double normal_stiffness(double delta, double r_eff) const { return 2 * e_star * std::sqrt(r_eff * delta); }
  double tangential_stiffness(double delta, double r_eff) const { return 8 * g_star * std::sqrt(r_eff * delta); }
  double elastic_energy(double delta, double r_eff) const {
    return 8.0 / 15.0 * e_star * std::sqrt(r_eff) * delta * delta * std::sqrt(delta);
  }
};

// Throws tg::InputError naming the offending parameter (ν outside (-1, 0.5],
// G <= 0, μ < 0, e outside (0, 1]).
HertzMindlin make_hertz_mindlin(const Material& a, const Material& b, double friction, double restitution);

// The geometry of one touching contact, seen from body i towards body j.
// T is double, or Lanes2 for two contacts at once (dem/lanes.hpp).
template <class T>
struct ContactGeometryT {
  Vec3T<T> n;        // unit normal from i to j
  T delta;           // overlap > 0, m
  T r_eff;           // R*, m
  T m_eff;           // m*, kg
  Vec3T<T> v_rel;    // velocity of j's contact point minus i's, m/s
};
using ContactGeometry = ContactGeometryT<double>;

template <class T>
struct ContactForceT {
  Vec3T<T> force_on_j;                                   // force on j (on i: the opposite), N
  T fn;                                                  // normal force magnitude (>= 0), N
  decltype(std::declval<T>() > std::declval<T>()) sliding;  // the Coulomb cap was active
};
using ContactForce = ContactForceT<double>;

template <class T, class M>
inline Vec3T<T> select(M m, Vec3T<T> a, Vec3T<T> b) {
  return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}

// Updates the tangential history `xi` (m, in place) and returns the force.
// Precondition: g.delta > 0, g.n unit, law from make_hertz_mindlin().
// Written with selects instead of branches, so that both lanes of a Lanes2
// take their own way; a branch is kept where it skips work that the lanes
// rarely need (the exact rescale, the Coulomb cap).
template <class T>
inline ContactForceT<T> hertz_mindlin_force(const HertzMindlin& law, const ContactGeometryT<T>& g, double dt, Vec3T<T>& xi) {
  const T zero{}, one = zero + 1.0;
  const T sq = lane_sqrt(g.r_eff * g.delta);
  const T kn = 2 * law.e_star * sq;
  const T kt = 8 * law.g_star * sq;
  const T vn = dot(g.v_rel, g.n);  // < 0 while approaching
  // Tsuji dashpot: c = 2 sqrt(5/6) |β| sqrt(k m*); 2 sqrt(5/6) = 1.8257...
  T cn = zero;
  if (law.damp_beta > 0) cn = 1.8257418583505538 * law.damp_beta * lane_sqrt(kn * g.m_eff);
  const T ct = cn * law.damp_t_over_n;
  T fn = 2.0 / 3.0 * kn * g.delta - cn * vn;  // 4/3 E* sqrt(R*) δ^{3/2} = 2/3 kn δ
  fn = select(fn < zero, zero, fn);

  // Keep ξ in the current tangent plane: drop its normal part, keep its
  // length (scale p by sqrt(ρ), ρ = |ξ|²/|p|²). The normal turns by ~1e-7 rad
  // a step, so ρ - 1 is ~1e-14: there sqrt(ρ) = 1 + e/2 - e²/8 (e = ρ - 1)
  // with a remainder e³/16 below half an ulp of 1 for e <= 1e-5, i.e. the
  // square root to rounding, without its latency on the contact's chain of
  // dependent operations (it was 7 % of the contact loop).
  const T xi_len2 = dot(xi, xi);
  const Vec3T<T> p = xi - dot(xi, g.n) * g.n;
  const T p_len2 = dot(p, p);
  const auto has = p_len2 > zero;  // else ξ is zero, along n (then dropped) or not finite (kept, caught later)
  const T rho = xi_len2 / select(has, p_len2, one), e = rho - 1.0;
  T scale = 1.0 + e * (0.5 - 0.125 * e);
  const auto far = e > 1e-5;
  if (any(far)) scale = select(far, lane_sqrt(rho), scale);
  xi = select(has, scale * p, select(xi_len2 > zero, Vec3T<T>{}, xi));

  const Vec3T<T> vt = g.v_rel - vn * g.n;
  xi = xi + dt * vt;
  Vec3T<T> ft = -1.0 * (kt * xi + ct * vt);
  const T ft_len2 = dot(ft, ft);
  const T cap = law.friction * fn;
  const auto sliding = ft_len2 > cap * cap;
  if (any(sliding)) {
    // Where sliding, |ft|² > cap² >= 0.
    const Vec3T<T> fs = (cap / lane_sqrt(select(sliding, ft_len2, one))) * ft;
    // ξ consistent with the capped force: -kt ξ - ct vt = ft.
    const auto stiff = kt > zero;
    const Vec3T<T> xs = (-1.0 / select(stiff, kt, one)) * (fs + ct * vt);
    ft = select(sliding, fs, ft);
    xi = select(sliding, select(stiff, xs, Vec3T<T>{}), xi);
  }
  return {fn * g.n + ft, fn, sliding};
}

}  // namespace tg::dem

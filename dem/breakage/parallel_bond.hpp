// Parallel bond of Potyondy & Cundall (2004, "A bonded-particle model for
// rock", doi:10.1016/j.ijrmms.2004.09.011): an elastic cement disc of radius
// R̄ between two spheres A and B, acting in parallel with (here: instead of)
// the contact law while intact. It carries a normal force F̄n, a shear force
// F̄s, a twisting moment M̄t and a bending moment M̄b, built up incrementally
// from the relative motion of the two spheres:
//   ΔF̄n = k̄n A ΔUn          (ΔUn = approach of B towards A, compression > 0)
//   ΔF̄s = −k̄s A ΔUs         (ΔUs = tangential displacement of B's bond point relative to A's)
//   ΔM̄t = −k̄s J Δθn,  ΔM̄b = −k̄n I Δθs   (Δθ = rotation of B relative to A)
// with A = πR̄², I = πR̄⁴/4, J = πR̄⁴/2. Before each increment F̄s and M̄b are
// rotated into the current plane of the bond (normal part removed, length
// kept), as the shear history of the Hertz–Mindlin law is.
// Peak stresses on the bond periphery (beam theory):
//   σmax = −F̄n/A + |M̄b| R̄/I,   τmax = |F̄s|/A + |M̄t| R̄/J
// and the bond breaks when σmax > σ̄c or τmax > τ̄c.
//
// Parameters of the reference study (§4.2, Table 1): k̄n = E/(RA+RB),
// k̄s = G/(RA+RB) (Pa/m; E = 2G(1+ν)); σ̄c = τ̄c = 3.3 MPa; radius multiplier
// λ = 1.25. The study defines λ = 1 as "the radius of the cross-section is the
// average of the radii of the two connected spheres", so by default
//   R̄ = λ (RA + RB)/2
// (BondRadiusRule::kMin gives the λ·min(RA, RB) of the original P&C paper and
// of PFC, which the study ran; the two agree for equal spheres; for the
// template's 0.45/0.26 pairs the study's form gives a bond ~35 % wider).
// Optional dashpots (bond_dashpot_force) damp the bond's relative motion.
//
// Sign conventions: n is the unit vector from A to B; F̄n > 0 is compression;
// the force on B is F̄n n + F̄s (on A: the opposite); the moment on B is
// M̄t n + M̄b (on A: the opposite) plus the moments of the forces about each
// centre, applied at the bond point (on the line of centres, midway through
// the gap). Cost: O(1) per bond per step, no allocation.
#pragma once
#include <algorithm>
#include <cmath>
#include <numbers>

#include "dem/vec3.hpp"

namespace tg::dem::breakage {

// Which radius λ multiplies: the study's "average of the radii" (λ = 1:
// R̄ = (RA + RB)/2) or P&C's and PFC's smaller radius (R̄ = λ min(RA, RB)).
// The two agree for equal spheres.
enum class BondRadiusRule { kMean, kMin };

struct ParallelBondParams {
  double radius_multiplier = 1.25;  // λ (Table 1)
  BondRadiusRule radius_rule = BondRadiusRule::kMean;  // the study's text
  // Bond dashpots: critical-damping ratio β of the bond's axial (k̄n A) and
  // shear (k̄s A) springs for the two-body oscillator (reduced mass m* =
  // mA mB/(mA + mB)), as PFC's parallel-bond dashpots and LIGGGHTS' bond
  // damping; 0 = none (an undamped spring network).
  double damping_ratio = 0;
  double youngs_modulus_Pa = 5.5e9;  // E = 2G(1+ν) with G = 2.2 GPa, ν = 0.25
  double shear_modulus_Pa = 2.2e9;   // G (Table 1)
  double tensile_strength_Pa = 3.3e6;  // σ̄c (Table 1)
  double shear_strength_Pa = 3.3e6;    // τ̄c (Table 1)
};

// Throws tg::InputError naming the parameter (non-positive or non-finite).
void validate(const ParallelBondParams& p);

// Geometry and stiffness of one bond, fixed at creation.
struct BondSection {
  double radius = 0;      // R̄, m
  double area = 0;        // A = πR̄², m²
  double inertia = 0;     // I = πR̄⁴/4, m⁴
  double polar = 0;       // J = πR̄⁴/2, m⁴
  double kn = 0, ks = 0;  // k̄n, k̄s per unit area, Pa/m
};

inline BondSection bond_section(const ParallelBondParams& p, double ra, double rb) {
  constexpr double pi = std::numbers::pi;
  BondSection s;
  s.radius = p.radius_multiplier * (p.radius_rule == BondRadiusRule::kMin ? std::min(ra, rb) : 0.5 * (ra + rb));
  const double r2 = s.radius * s.radius;
  s.area = pi * r2;
  s.inertia = pi * r2 * r2 / 4;
  s.polar = pi * r2 * r2 / 2;
  s.kn = p.youngs_modulus_Pa / (ra + rb);
  s.ks = p.shear_modulus_Pa / (ra + rb);
  return s;
}

// Internal forces of one bond (the state a snapshot/checkpoint carries).
struct BondState {
  double fn = 0;  // normal force, N (compression > 0)
  Vec3 fs;        // shear force on B, N
  double mt = 0;  // twisting moment on B about n, N·m
  Vec3 mb;        // bending moment on B, N·m
};

// Relative motion of the two spheres over one step.
struct BondKinematics {
  Vec3 n;        // unit normal A → B (current)
  Vec3 v_rel;    // velocity of B's bond point minus A's, m/s
  Vec3 w_rel;    // ωB − ωA, rad/s
};

namespace detail {
// Keeps v in the plane normal to n with its length unchanged.
inline Vec3 rotate_into_plane(Vec3 v, Vec3 n) {
  const double len2 = dot(v, v);
  if (len2 == 0) return v;
  const Vec3 p = v - dot(v, n) * n;
  const double p2 = dot(p, p);
  return p2 > 0 ? std::sqrt(len2 / p2) * p : Vec3{};
}
}  // namespace detail

// One incremental update over dt (precondition: n unit, section from bond_section()).
inline void update_bond(const BondSection& s, const BondKinematics& k, double dt, BondState& b) {
  const double vn = dot(k.v_rel, k.n);  // > 0 while separating
  const Vec3 vs = k.v_rel - vn * k.n;
  const double wn = dot(k.w_rel, k.n);
  const Vec3 ws = k.w_rel - wn * k.n;
  b.fn += -s.kn * s.area * vn * dt;
  b.fs = detail::rotate_into_plane(b.fs, k.n) - (s.ks * s.area * dt) * vs;
  b.mt += -s.ks * s.polar * wn * dt;
  b.mb = detail::rotate_into_plane(b.mb, k.n) - (s.kn * s.inertia * dt) * ws;
}

struct BondStress {
  double sigma_max = 0;  // peak tensile normal stress, Pa (tension > 0)
  double tau_max = 0;    // peak shear stress, Pa
};

inline BondStress bond_stress(const BondSection& s, const BondState& b) {
  return {-b.fn / s.area + norm(b.mb) * s.radius / s.inertia, norm(b.fs) / s.area + std::abs(b.mt) * s.radius / s.polar};
}

inline bool bond_breaks(const ParallelBondParams& p, const BondSection& s, const BondState& b) {
  const BondStress st = bond_stress(s, b);
  return st.sigma_max > p.tensile_strength_Pa || st.tau_max > p.shear_strength_Pa;
}

// Spring constants of the bond as seen by the time-step estimate:
// translational k̄n A (N/m) and rotational k̄n I (N·m/rad).
inline double bond_axial_stiffness(const BondSection& s) { return s.kn * s.area; }
inline double bond_bending_stiffness(const BondSection& s) { return s.kn * s.inertia; }

// Dashpot force on B (p.damping_ratio = β > 0): −c_n v_n n − c_s v_s with
// c = 2β√(m* k) for k = k̄n A (normal) and k̄s A (shear), v the relative
// velocity of the bond points (k.v_rel); m* the reduced mass. It acts at the
// bond point in parallel with the bond and holds no state: not part of the
// bond's force (F̄n, F̄s) or of its peak stresses (as PFC's dashpots, which
// act beside the bond's spring forces).
inline Vec3 bond_dashpot_force(const ParallelBondParams& p, const BondSection& s, const BondKinematics& k, double m_eff) {
  const double vn = dot(k.v_rel, k.n);
  const Vec3 vs = k.v_rel - vn * k.n;
  const double cn = 2 * p.damping_ratio * std::sqrt(m_eff * s.kn * s.area);
  const double cs = 2 * p.damping_ratio * std::sqrt(m_eff * s.ks * s.area);
  return -(cn * vn) * k.n - cs * vs;
}

// Forces and moments on the two spheres, given the bond point c and the
// centres; `extra`: a force on B at c besides the bond's (its dashpot;
// none: the bond's force alone, not a sum with zero).
struct BondLoads {
  Vec3 force_on_b;  // on A: −force_on_b
  Vec3 torque_on_a, torque_on_b;
};
inline BondLoads bond_loads(const BondState& b, Vec3 n, Vec3 xa, Vec3 xb, Vec3 c, const Vec3* extra = nullptr) {
  Vec3 f = b.fn * n + b.fs;
  if (extra) f = f + *extra;
  const Vec3 m = b.mt * n + b.mb;
  return {f, cross(c - xa, -f) - m, cross(c - xb, f) + m};
}

// Bond point: on the line of centres, midway through the gap (the contact
// point for touching spheres).
inline Vec3 bond_point(Vec3 xa, double ra, Vec3 xb, double rb) {
  const Vec3 d = xb - xa;
  const double len = norm(d);
  const double t = (ra + 0.5 * (len - ra - rb)) / len;
  return xa + t * d;
}

}  // namespace tg::dem::breakage

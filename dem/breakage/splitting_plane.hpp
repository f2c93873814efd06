// Splitting plane of a breaking sphere (reference study §3.2).
//
// Average stress of the sphere from its contacts (Eq. 1 of the study):
//   s_ij = (1/V) Σ_c (x_i^c − x_i^p) F_j^c,   F^c = force ON the sphere.
// A compressive contact has its force pointing inwards, against the branch
// vector, so s is negative in compression. We report it in the soil-mechanics
// convention, COMPRESSION POSITIVE: σ = −sym(s). Principal values
// σ1 ≥ σ2 ≥ σ3 (Eigen's self-adjoint solver, ascending); σ3 is the minor,
// least compressive (or most tensile) principal stress.
//
// The plane passes through the centre and the contact of maximum normal
// force (n_f = unit vector from the centre to that contact point; the normal
// force acts along it), and is perpendicular to the plane spanned by n_f and
// the σ3 direction e3. A plane perpendicular to span(n_f, e3) has its normal
// in that span; containing n_f, its normal is also ⟂ n_f. Hence
//   normal = e3 − (e3·n_f) n_f, normalised
// i.e. the sphere opens in its least compressed direction and the crack
// contains the largest force (a Brazilian split).
//
// Deterministic choices, in order (tolerance: relative 1e-6 of the largest
// |σ| for equal eigenvalues, 1e-6 for parallel unit vectors):
//  1. σ3 simple, e3 not ∥ n_f: the rule above (rule = kSigma3).
//  2. σ3 simple, e3 ∥ n_f: use e2 instead (⟂ e3, hence ⟂ n_f) (kSigma2).
//  3. σ3 double (σ2 = σ3 < σ1, e.g. one grain between two platens): every
//     direction of span(e2, e3) is a σ3 direction; the one ⟂ n_f is
//     e1 × n_f (kDegenerate); when n_f ∥ e1 that whole plane is ⟂ n_f and
//     rule 4 picks the direction.
//  4. isotropic stress or the cases above: the first of the global axes
//     x, y, z whose component ⟂ n_f (and ⟂ e1 in case 3) is longer than 0.5,
//     projected and normalised (kFixedAxis).
// The normal's sign is fixed: its largest-magnitude component is positive.
// Cost: O(number of contacts) + one 3×3 eigen-solve.
#pragma once
#include <optional>
#include <span>

#include <Eigen/Core>

#include "dem/vec3.hpp"

namespace tg::dem::breakage {

struct ContactLoad {
  Vec3 point;  // contact point, m
  Vec3 force;  // force on the sphere, N
};

enum class PlaneRule { kSigma3, kSigma2, kDegenerate, kFixedAxis };

struct SplittingPlane {
  Vec3 centre;                 // a point of the plane (the sphere centre), m
  Vec3 normal;                 // unit normal of the plane
  Vec3 n_f;                    // unit vector centre → contact of maximum normal force
  double f_max = 0;            // that normal force, N (compression > 0)
  int contact = -1;            // its index in the input
  Eigen::Matrix3d stress;      // σ, Pa, compression positive
  Eigen::Vector3d principal;   // σ3, σ2, σ1 (ascending), Pa
  Eigen::Matrix3d directions;  // columns: e3, e2, e1
  PlaneRule rule = PlaneRule::kSigma3;
};

// Average stress tensor, compression positive (Pa): −sym((1/V) Σ (x^c − x^p) ⊗ F^c).
Eigen::Matrix3d average_stress(Vec3 centre, double volume, std::span<const ContactLoad> contacts);

// The plane of the study; nullopt when no contact pushes on the sphere
// (maximum normal force ≤ 0). Preconditions: volume > 0, finite input.
std::optional<SplittingPlane> splitting_plane(Vec3 centre, double volume, std::span<const ContactLoad> contacts);

}  // namespace tg::dem::breakage

#include "dem/breakage/splitting_plane.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

namespace tg::dem::breakage {
namespace {

Vec3 to_vec(const Eigen::Vector3d& v) { return {v(0), v(1), v(2)}; }

Vec3 unit(Vec3 v) { return (1 / norm(v)) * v; }

// Sign rule: the largest-magnitude component is positive (ties: first).
Vec3 canonical_sign(Vec3 v) {
  const double c[3] = {v.x, v.y, v.z};
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(c[i]) > std::abs(c[k])) k = i;
  return c[k] < 0 ? -v : v;
}

// Rule 4: first global axis with a component longer than 0.5 after removing
// its parts along the given unit vectors (which are mutually orthogonal).
Vec3 fixed_axis(Vec3 a_perp, const Vec3* b_perp) {
  const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const Vec3& a : axes) {
    Vec3 p = a - dot(a, a_perp) * a_perp;
    if (b_perp) p = p - dot(p, *b_perp) * *b_perp;
    if (norm(p) > 0.5) return unit(p);
  }
  // Unreachable for one or two orthonormal vectors: some axis keeps |p|² ≥ 1/3.
  return axes[0];
}

}  // namespace

Eigen::Matrix3d average_stress(Vec3 centre, double volume, std::span<const ContactLoad> contacts) {
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const auto& c : contacts) {
    const Eigen::Vector3d b(c.point.x - centre.x, c.point.y - centre.y, c.point.z - centre.z);
    const Eigen::Vector3d f(c.force.x, c.force.y, c.force.z);
    s += b * f.transpose();
  }
  s /= volume;
  return -0.5 * (s + s.transpose());
}

std::optional<SplittingPlane> splitting_plane(Vec3 centre, double volume, std::span<const ContactLoad> contacts) {
  SplittingPlane out;
  out.centre = centre;
  for (int i = 0; i < static_cast<int>(contacts.size()); ++i) {
    const Vec3 b = contacts[i].point - centre;
    const double len = norm(b);
    if (!(len > 0)) continue;
    const double fn = -dot(contacts[i].force, b) / len;  // inward push > 0
    if (fn > out.f_max) {
      out.f_max = fn;
      out.contact = i;
      out.n_f = (1 / len) * b;
    }
  }
  if (out.contact < 0) return std::nullopt;

  out.stress = average_stress(centre, volume, contacts);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(out.stress);
  out.principal = es.eigenvalues();
  out.directions = es.eigenvectors();
  const Vec3 e3 = to_vec(out.directions.col(0)), e2 = to_vec(out.directions.col(1)), e1 = to_vec(out.directions.col(2));
  const double scale = out.principal.cwiseAbs().maxCoeff();
  const double tol = 1e-6 * scale;
  const bool iso = out.principal(2) - out.principal(0) <= tol;
  const bool double3 = !iso && out.principal(1) - out.principal(0) <= tol;
  const Vec3 nf = out.n_f;
  constexpr double kPar = 1e-6;

  Vec3 normal;
  if (iso) {
    normal = fixed_axis(nf, nullptr);
    out.rule = PlaneRule::kFixedAxis;
  } else if (double3) {
    const Vec3 c = cross(e1, nf);
    if (norm(c) > kPar) {
      normal = unit(c);
      out.rule = PlaneRule::kDegenerate;
    } else {
      normal = fixed_axis(nf, nullptr);  // n_f ∥ e1: ⟂ n_f is ⟂ e1 too
      out.rule = PlaneRule::kFixedAxis;
    }
  } else {
    const Vec3 p3 = e3 - dot(e3, nf) * nf;
    if (norm(p3) > kPar) {
      normal = unit(p3);
      out.rule = PlaneRule::kSigma3;
    } else {
      normal = unit(e2 - dot(e2, nf) * nf);
      out.rule = PlaneRule::kSigma2;
    }
  }
  out.normal = canonical_sign(normal);
  return out;
}

}  // namespace tg::dem::breakage

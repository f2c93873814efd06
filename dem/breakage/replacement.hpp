// Replacement of a broken sphere by two fragments (reference study §3.2).
//
// The fragment template (fragment_template.hpp, unit mother radius, fragment
// on the z > 0 side) is scaled by the mother's radius R and placed in the
// frame of the splitting plane:
//   ez = plane normal,  ex = n_f (the direction of the largest force, which
//   lies in the plane),  ey = ez × ex;
// fragment 0 is the template itself (on the +ez side), fragment 1 its mirror
// image through the plane (z → −z), so that the A sphere of azimuth 0 of each
// fragment faces the contact of maximum force. Bonds join spheres of the
// same fragment only: none crosses the plane.
//
// Kinematics: every new sphere takes the mother's rigid-body field,
// v_k = v + ω × (x_k − x_c), ω_k = ω, so bonded neighbours start with zero
// relative normal velocity and the bonds start unloaded. Total momentum of
// the fragments is m_retained·v (the two fragments are symmetric about x_c).
//
// Overlap: every new sphere lies inside the mother (|x_k − x_c| + r_k ≤ R),
// so by the triangle inequality its overlap with any neighbour sphere or
// wall is at most the mother's overlap with it: replacement never creates
// overlap that was not there.
//
// Mass: ~46 % of the mother's volume is removed (recorded, never redistributed).
// Cost: O(34) per replacement.
#pragma once
#include <array>
#include <vector>

#include "dem/vec3.hpp"

namespace tg::dem::breakage {

struct Mother {
  Vec3 x;      // centre, m
  double r;    // radius, m
  Vec3 v;      // velocity, m/s
  Vec3 w;      // angular velocity, rad/s
};

struct NewSphere {
  Vec3 x, v, w;
  double r = 0;
  int fragment = 0;  // 0 (+normal side) or 1
  int slot = 0;      // 0..33: fragment*17 + template index
};

struct Replacement {
  std::array<NewSphere, 34> spheres;
  std::vector<std::array<int, 2>> bonds;  // pairs of indices into spheres (80)
  double volume_mother = 0, volume_retained = 0, volume_lost = 0;  // m³
};

// Preconditions: normal unit, n_f unit and ⟂ normal (as splitting_plane()
// returns them; n_f is re-orthogonalised here against round-off), r > 0.
Replacement replace_sphere(const Mother& mother, Vec3 normal, Vec3 n_f);

}  // namespace tg::dem::breakage

// The fragment template of the sequential breakage model (reference study
// §3.2, Fig. 6): one of the two fragments that replace a broken sphere, as a
// cluster of 17 bonded spheres inside the upper half (z > 0) of the mother
// sphere of radius 1, cut by the splitting plane z = 0.
//
// Construction (every sphere touches the mother from inside, none crosses
// the plane, and every bonded pair is exactly tangent so that no contact
// force is locked in at creation and plain Hertz contact takes over cleanly
// when a bond breaks):
//   ring A: 8 spheres of radius ra at azimuths k·45°, each tangent to the
//           mother (|c| + ra = 1), to the plane (c_z = ra) and to its two
//           ring neighbours: (1 − 2 ra) sin²(π/8) = ra² → ra = 0.26330...
//   centre: 1 sphere of radius rc at (0, 0, rc), tangent to the plane and to
//           every A sphere: rc = (1 − 2 ra) / (4 ra) = 0.44948...
//   ring B: 8 spheres of radius rb at azimuths 22.5° + k·45°, each tangent to
//           the mother, to the central sphere and to its two A neighbours
//           (rb = 0.16097..., solved by bisection; polar angle of the centre 45°).
// The A ring and the central sphere are the 1 + 8 spheres on the plane (the
// flat fracture face); ring B caps the dome. Bonds: the 40 tangent pairs
// (8 centre–A, 8 centre–B, 8 A–A, 16 A–B); no other pair touches (the
// smallest gap between unbonded spheres is 0.132).
//
// Because no two spheres overlap, the union volume is the plain sum of the
// sphere volumes: the two fragments retain 2 Σ r³ = 0.5404 of the mother's
// volume (45.96 % lost; the study: 46 %, below the 47 % limit of Ciantia et al.).
// The tests check that fraction against an independent grid count of the union.
//
// Cost: built once (microseconds); scaled and rotated per replacement.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "dem/vec3.hpp"

namespace tg::dem::breakage {

struct TemplateSphere {
  Vec3 c;    // centre, in mother radii (fragment on the z > 0 side)
  double r;  // radius, in mother radii
};

struct FragmentTemplate {
  static constexpr int kSpheres = 17;
  std::array<TemplateSphere, kSpheres> spheres;       // [0] centre, [1..8] ring A, [9..16] ring B
  std::vector<std::array<int, 2>> bonds;               // tangent pairs (i < j), 40 of them
  double ra = 0, rb = 0, rc = 0;                       // the three radii
  // Fraction of the mother's volume kept by BOTH fragments (2 Σ r³).
  double retained_fraction() const;
  // Mass centre of the fragment (uniform density), in mother radii.
  Vec3 centroid() const;
};

// The template (computed once, cached; thread-safe static initialisation).
const FragmentTemplate& fragment_template();

}  // namespace tg::dem::breakage

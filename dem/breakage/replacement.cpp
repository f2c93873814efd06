#include "dem/breakage/replacement.hpp"

#include <cmath>
#include <numbers>

#include "dem/breakage/fragment_template.hpp"

namespace tg::dem::breakage {

Replacement replace_sphere(const Mother& mother, Vec3 normal, Vec3 n_f) {
  const FragmentTemplate& t = fragment_template();
  const Vec3 ez = normal;
  Vec3 ex = n_f - dot(n_f, ez) * ez;
  ex = (1 / norm(ex)) * ex;
  const Vec3 ey = cross(ez, ex);

  Replacement out;
  const double R = mother.r;
  double sum_r3 = 0;
  for (int f = 0; f < 2; ++f) {
    const double side = f == 0 ? 1.0 : -1.0;
    for (int k = 0; k < FragmentTemplate::kSpheres; ++k) {
      const TemplateSphere& s = t.spheres[k];
      NewSphere& n = out.spheres[f * FragmentTemplate::kSpheres + k];
      const Vec3 rel = R * (s.c.x * ex + s.c.y * ey + (side * s.c.z) * ez);
      n.x = mother.x + rel;
      n.r = R * s.r;
      n.v = mother.v + cross(mother.w, rel);
      n.w = mother.w;
      n.fragment = f;
      n.slot = f * FragmentTemplate::kSpheres + k;
      sum_r3 += n.r * n.r * n.r;
    }
    for (auto b : t.bonds) out.bonds.push_back({f * FragmentTemplate::kSpheres + b[0], f * FragmentTemplate::kSpheres + b[1]});
  }
  constexpr double k43pi = 4.0 / 3.0 * std::numbers::pi;
  out.volume_mother = k43pi * R * R * R;
  out.volume_retained = k43pi * sum_r3;
  out.volume_lost = out.volume_mother - out.volume_retained;
  return out;
}

}  // namespace tg::dem::breakage

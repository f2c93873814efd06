#include "dem/packing_io.hpp"

namespace tg::dem {

Particles particles_from_spheres(const SphereTable& s, double density) {
  Particles p;
  for (size_t i = 0; i < s.size(); ++i) p.append_sphere(s.x_m[i], s.y_m[i], s.z_m[i], s.r_m[i], density, s.particle[i]);
  return p;
}

Particles read_packing_csv(const std::filesystem::path& path, double density) {
  return particles_from_spheres(read_spheres(path.string()), density);
}

SphereTable spheres_of(const Particles& p) {
  SphereTable s;
  s.x_m = p.x;
  s.y_m = p.y;
  s.z_m = p.z;
  s.r_m = p.r;
  s.particle = p.particle;
  return s;
}

void write_packing_csv(const Particles& p, const std::filesystem::path& path) { write_spheres(spheres_of(p), path); }

}  // namespace tg::dem

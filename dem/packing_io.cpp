#include "dem/packing_io.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "core/table.hpp"

namespace tg::dem {

Particles read_packing_csv(const std::filesystem::path& path, double density) {
  const Table t = read_csv(path, {"x_m", "y_m", "z_m", "r_m"});
  const auto &x = t.num("x_m"), &y = t.num("y_m"), &z = t.num("z_m"), &r = t.num("r_m");
  const bool has_id = t.has("particle") && !t.columns()[static_cast<size_t>(t.find("particle"))].is_text;
  Particles p;
  for (int64_t i = 0; i < t.rows(); ++i) {
    if (!(r[i] > 0) || !std::isfinite(r[i] + x[i] + y[i] + z[i]))
      throw InputError(path.string() + ":" + std::to_string(i + 2) + ": sphere needs finite x_m,y_m,z_m and r_m > 0");
    p.append_sphere(x[i], y[i], z[i], r[i], density, has_id ? static_cast<int64_t>(t.num("particle")[i]) : i);
  }
  if (p.size() == 0) throw InputError(path.string() + ": packing has no spheres");
  return p;
}

void write_packing_csv(const Particles& p, const std::filesystem::path& path) {
  Table t;
  t.add("x_m", p.x);
  t.add("y_m", p.y);
  t.add("z_m", p.z);
  t.add("r_m", p.r);
  write_csv(t, path);
}

}  // namespace tg::dem

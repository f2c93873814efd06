#include "core/sphere_table.hpp"

#include <cmath>
#include <unordered_set>

#include "core/errors.hpp"
#include "core/io/dem_text.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"

namespace tg {

SphereTable spheres_from_table(const Table& t) {
  const auto &x = t.num("x_m"), &y = t.num("y_m"), &z = t.num("z_m"), &r = t.num("r_m");
  const char* id_col = t.has("particle") ? "particle" : t.has("cluster") ? "cluster" : nullptr;
  const std::vector<double>* ids = id_col ? &t.num(id_col) : nullptr;
  SphereTable s;
  s.source = t.source;
  for (int64_t q = 0; q < t.rows(); ++q) {
    const std::string row = t.source + ": row " + std::to_string(q + 2);
    if (!std::isfinite(x[q]) || !std::isfinite(y[q]) || !std::isfinite(z[q]))
      throw InputError(row + ": sphere position must be finite");
    if (!(r[q] > 0) || !std::isfinite(r[q])) throw InputError(row + ": r_m must be > 0");
    int64_t id = q;
    if (ids) {
      const double v = (*ids)[q];
      if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > 9e15)
        throw InputError(row + ": " + id_col + " id must be an integer");
      id = static_cast<int64_t>(v);
    }
    s.push_back(x[q], y[q], z[q], r[q], id);
  }
  if (s.size() == 0) throw InputError(t.source + ": no spheres");
  return s;
}

Table spheres_to_table(const SphereTable& s) {
  Table t;
  t.add("x_m", s.x_m);
  t.add("y_m", s.y_m);
  t.add("z_m", s.z_m);
  t.add("r_m", s.r_m);
  t.add("particle", std::vector<double>(s.particle.begin(), s.particle.end()));
  return t;
}

SphereTable read_spheres(const std::string& path) {
  if (!is_hdf5(path)) {
    if (std::optional<Table> other = read_dem_text(path)) return spheres_from_table(*other);
    return spheres_from_table(read_csv(path, {"x_m", "y_m", "z_m", "r_m"}));
  }
  const auto [file, ds] = split_dataset_spec(path);
  std::string group = ds;
  H5Reader rd(file);
  if (group.empty()) {
    for (const std::string& d : rd.datasets()) {
      const auto slash = d.rfind('/');
      if (slash != std::string::npos && d.substr(slash + 1) == "x_m") {
        group = d.substr(0, slash);
        break;
      }
    }
    if (group.empty()) throw InputError(file + ": no table with an x_m column (expected spheres x_m,y_m,z_m,r_m)");
  }
  Table t = rd.read_table(group);
  t.source = file + ":" + group;
  return spheres_from_table(t);
}

void write_spheres(const SphereTable& s, const std::filesystem::path& path) { write_csv(spheres_to_table(s), path); }

int64_t particle_count(const SphereTable& s) {
  return static_cast<int64_t>(std::unordered_set<int64_t>(s.particle.begin(), s.particle.end()).size());
}

}  // namespace tg

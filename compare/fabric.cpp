#include "compare/fabric.hpp"

#include <cmath>

namespace tg::compare {

ContactSeries contact_series(std::span<const std::pair<int64_t, int64_t>> pairs,
                             std::span<const Eigen::Vector3d> normals) {
  ContactSeries c;
  c.measured = true;
  std::vector<double> a, b, nz, ny, nx;
  for (size_t k = 0; k < normals.size(); ++k) {
    a.push_back(static_cast<double>(pairs[k].first));
    b.push_back(static_cast<double>(pairs[k].second));
    nz.push_back(normals[k][0]);
    ny.push_back(normals[k][1]);
    nx.push_back(normals[k][2]);
  }
  c.contacts.add("a", std::move(a));
  c.contacts.add("b", std::move(b));
  c.contacts.add("normal_z", std::move(nz));
  c.contacts.add("normal_y", std::move(ny));
  c.contacts.add("normal_x", std::move(nx));
  c.fabric = measure::fabric(normals);
  int64_t near = 0;
  for (const auto& n : normals) near += measure::polar_angle_deg(n) <= kNearAxisDeg;
  c.near_axis_share = normals.empty() ? std::nan("") : static_cast<double>(near) / static_cast<double>(normals.size());
  c.polar = measure::polar_histogram(normals, measure::equal_solid_angle_edges_deg(kPolarBands));
  return c;
}

double mean_coordination(std::span<const measure::SizeClass> by_size) {
  double sum = 0;
  int64_t n = 0;
  for (const auto& c : by_size) sum += c.mean_coordination * static_cast<double>(c.particles), n += c.particles;
  return n ? sum / static_cast<double>(n) : std::nan("");
}

std::vector<measure::SizeClass> coordination_by_size(const Table& t) {
  if (!t.has("d_eq_mm") || !t.has("coordination") || !t.has("touches_border")) return {};
  const auto &d = t.num("d_eq_mm"), &z = t.num("coordination"), &b = t.num("touches_border");
  std::vector<double> size, coord;
  for (int64_t q = 0; q < t.rows(); ++q)
    if (b[q] == 0 && z[q] >= 0) size.push_back(d[q]), coord.push_back(z[q]);
  return measure::coordination_by_size(size, coord);
}

}  // namespace tg::compare

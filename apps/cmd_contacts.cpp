// tomograin contacts LABELS -o contacts.csv   touching pairs, coordination, fabric
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>

#include "apps/command.hpp"
#include "apps/jobs.hpp"
#include "core/atomic_file.hpp"
#include "core/errors.hpp"
#include "core/table.hpp"
#include "measure/contacts.hpp"
#include "measure/label_stats.hpp"

namespace cmd_contacts {

namespace fs = std::filesystem;
using namespace tg;

struct Opts {
  std::string in, out, summary;
  double voxel_um = 0, normal_radius = 9.0;
  int threads = 0;
};

nlohmann::json matrix(const Eigen::Matrix3d& m) {
  nlohmann::json j = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) j.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return j;
}

int run_contacts(const Opts& o) {
  if (fs::path(o.out).extension() != ".csv") throw UsageError("-o " + o.out + ": expected a .csv file");
  const std::string summary = !o.summary.empty() ? o.summary : app::beside(o.out, "_fabric.json");
  if (fs::path(summary).extension() != ".json") throw UsageError("--summary " + summary + ": expected a .json file");
  const Volume<uint32_t> labels = app::read_labels(o.in, o.voxel_um);

  measure::ContactOptions co;
  co.threads = o.threads;
  co.normal_radius_voxels = o.normal_radius;
  const auto res = measure::find_contacts(labels.view(), co);
  measure::LabelStatsOptions so;
  so.collect_surface = false;
  so.threads = o.threads;
  const auto stats = measure::label_stats(labels.view(), so);

  Table t;
  auto col = [&](const std::string& name, auto f) {
    std::vector<double> v;
    for (const auto& c : res.contacts) v.push_back(static_cast<double>(f(c)));
    t.add(name, std::move(v));
  };
  using C = measure::Contact;
  col("label_a", [](const C& c) { return c.a; });
  col("label_b", [](const C& c) { return c.b; });
  col("area_m2", [](const C& c) { return c.area_m2; });
  col("normal_z", [](const C& c) { return c.normal[0]; });
  col("normal_y", [](const C& c) { return c.normal[1]; });
  col("normal_x", [](const C& c) { return c.normal[2]; });
  col("point_z_m", [](const C& c) { return c.point_m[0]; });
  col("point_y_m", [](const C& c) { return c.point_m[1]; });
  col("point_x_m", [](const C& c) { return c.point_m[2]; });
  col("crossings", [](const C& c) { return c.crossings; });
  col("face_to_face", [](const C& c) { return c.face_to_face ? 1 : 0; });

  // Per-particle coordination, the fabric and the normals' rose.
  std::vector<uint32_t> ids;
  for (const auto& s : stats.labels) ids.push_back(s.label);
  const auto z = measure::coordination(res.contacts, ids);
  std::vector<Eigen::Vector3d> normals;
  for (const auto& c : res.contacts) normals.push_back(c.normal);
  const auto f = measure::fabric(normals);
  double zsum = 0, zin = 0;
  int64_t nin = 0;
  std::vector<int64_t> zhist;
  for (size_t n = 0; n < z.size(); ++n) {
    zsum += z[n];
    if (static_cast<size_t>(z[n]) >= zhist.size()) zhist.resize(static_cast<size_t>(z[n]) + 1, 0);
    ++zhist[static_cast<size_t>(z[n])];
    if (!stats.labels[n].touches_border) {
      zin += z[n];
      ++nin;
    }
  }
  // Rose: share of normals per 10-degree band of the angle from z (sign-free),
  // beside the share an isotropic set would have (cos of the band's edges).
  nlohmann::json rose = nlohmann::json::array();
  std::vector<int64_t> band(9, 0);
  for (const auto& n : normals) {
    const double deg = std::acos(std::min(1.0, std::abs(n[0]))) * 180 / std::numbers::pi;
    ++band[static_cast<size_t>(std::min(8, static_cast<int>(deg / 10)))];
  }
  for (int b = 0; b < 9; ++b) {
    const double iso = std::cos(b * std::numbers::pi / 18) - std::cos((b + 1) * std::numbers::pi / 18);
    rose.push_back({{"from_deg", 10 * b}, {"to_deg", 10 * (b + 1)}, {"count", band[static_cast<size_t>(b)]},
                    {"share", normals.empty() ? 0.0 : static_cast<double>(band[static_cast<size_t>(b)]) / normals.size()},
                    {"isotropic_share", iso}});
  }
  // Coordination by size class: quartiles of d_eq.
  nlohmann::json by_size = nlohmann::json::array();
  if (!ids.empty()) {
    std::vector<size_t> order(ids.size());
    for (size_t n = 0; n < order.size(); ++n) order[n] = n;
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) { return stats.labels[x].d_eq_m < stats.labels[y].d_eq_m; });
    for (int q = 0; q < 4; ++q) {
      const size_t a = order.size() * static_cast<size_t>(q) / 4, b = order.size() * static_cast<size_t>(q + 1) / 4;
      if (a == b) continue;
      double s = 0;
      for (size_t k = a; k < b; ++k) s += z[order[k]];
      by_size.push_back({{"d_eq_from_mm", stats.labels[order[a]].d_eq_m * 1e3},
                         {"d_eq_to_mm", stats.labels[order[b - 1]].d_eq_m * 1e3},
                         {"particles", b - a},
                         {"mean_coordination", s / static_cast<double>(b - a)}});
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j;
  j["input"] = o.in;
  j["voxel_size_m"] = labels.geometry().voxel_size_m;
  j["particles"] = ids.size();
  j["contacts"] = res.contacts.size();
  j["mean_coordination"] = num(ids.empty() ? nan : 2.0 * static_cast<double>(res.contacts.size()) / ids.size());
  j["mean_coordination_interior"] = num(nin ? zin / nin : nan);
  j["interior_particles"] = nin;
  j["coordination_histogram"] = zhist;
  j["coordination_by_d_eq_quartile"] = by_size;
  j["fabric"] = {{"convention",
                  "N = <n n> (z,y,x); deviator D = N - I/3; F = 15/2 D; anisotropy a = sqrt(3/2 F:F) (SPAM); "
                  "0 = isotropic, 7.5 = all normals along one axis"},
                 {"N", matrix(f.N)},
                 {"deviator", matrix(f.deviator)},
                 {"F", matrix(f.F)},
                 {"anisotropy", num(f.anisotropy)},
                 {"eigenvalues", {num(f.eigenvalues[0]), num(f.eigenvalues[1]), num(f.eigenvalues[2])}},
                 {"major_axis_zyx", {num(f.major_axis[0]), num(f.major_axis[1]), num(f.major_axis[2])}}};
  j["normal_rose_from_z"] = rose;
  j["method"] =
      "contacts: labels within one watershed line (measure/contacts.hpp); normal from a to b between the "
      "centroids of a and b inside a ball of radius " + fmt::format("{:g}", o.normal_radius) +
      " voxels around the contact; area = crossings along the dominant axis x face area / |n_axis|";
  zsum = zsum / std::max<double>(1.0, static_cast<double>(z.size()));

  write_csv(t, o.out);
  {
    AtomicPath js(summary);
    std::ofstream os(js.temp());
    os << j.dump(2) << "\n";
    os.close();
    if (!os) throw InputError(summary + ": cannot write");
    js.commit();
  }
  fmt::print("{}: {} particles, {} contacts, mean coordination {:.3f} ({:.3f} for the {} not touching the border), "
             "fabric anisotropy a = {:.4f}\n",
             o.in, ids.size(), res.contacts.size(), zsum, nin ? zin / nin : nan, nin, f.anisotropy);
  fmt::print("wrote {} and {}\n", o.out, summary);
  return 0;
}

}  // namespace cmd_contacts

namespace cmd_contacts {
static tg::app::Registrar reg{{"contacts", 42,
      "Touching particles of a label volume: contact area, normal and point, coordination, fabric.\n\n"
      "Two labels touch when they share faces or are separated by at most one watershed line (the\n"
      "void line `segment` draws: 1 to 3 voxels along an axis, depending on its direction).\n"
      "Writes OUT.csv, one row per touching pair: label_a < label_b, area_m2, the unit normal\n"
      "normal_z/y/x from a to b, the contact point point_z/y/x_m, crossings (lattice lines through\n"
      "the interface) and face_to_face; and OUT_fabric.json: coordination (mean, interior, histogram,\n"
      "by size quartile), the fabric tensor N = <n n>, its deviator, F = 15/2 dev N and the\n"
      "anisotropy a = sqrt(3/2 F:F), and a rose of the normals' angle from z.\n"
      "Method and measured accuracy: measure/contacts.hpp, docs/measure.md.\n\n"
      "Examples:\n"
      "  tomograin contacts labels.h5 -o contacts.csv\n"
      "  tomograin contacts labels.tif --voxel-um 11.6 -o contacts.csv --summary fabric.json",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("labels", o->in, "Label volume (u32): .h5[:/dataset], .tif, folder of slices, raw .json")->required();
  sub->add_option("-o,--output", o->out, "Contact table (.csv)")->required();
  sub->add_option("--summary", o->summary, "Coordination and fabric (.json; default OUT_fabric.json)");
  sub->add_option("--normal-radius-vox", o->normal_radius,
                  "Radius (voxels) of the ball whose a- and b-centroids give the normal")
      ->check(CLI::Range(2.0, 64.0))
      ->default_str("9");
  tg::app::add_threads_option(sub, o->threads);
  tg::app::add_voxel_option(sub, o->voxel_um);
  return [o] { return run_contacts(*o); };
}}};
}  // namespace cmd_contacts

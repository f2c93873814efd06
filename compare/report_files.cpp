#include "compare/report_files.hpp"

#include <fmt/core.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include "core/atomic_file.hpp"
#include "core/errors.hpp"
#include "core/table.hpp"
#include "measure/grading.hpp"

#ifndef TOMOGRAIN_REPORT_SCRIPT
#define TOMOGRAIN_REPORT_SCRIPT ""
#endif

namespace tg::compare {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// JSON has no NaN: null instead.
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json distances_json(const Distances& d) {
  return {{"psd_ks", num(d.psd_ks)}, {"psd_w1_mm", num(d.psd_w1_mm)}, {"fr_ks", num(d.fr_ks)},
          {"fr_w1", num(d.fr_w1)},   {"ar_ks", num(d.ar_ks)},         {"ar_w1", num(d.ar_w1)}};
}

template <class T>
const char* npy_descr();
template <>
const char* npy_descr<uint16_t>() { return "<u2"; }
template <>
const char* npy_descr<uint32_t>() { return "<u4"; }

// NumPy format 1.0: magic, header length, a Python dict literal padded so the
// data starts on a 64-byte boundary, then the raw little-endian values.
template <class T>
void write_npy(const fs::path& path, const std::vector<T>& v, int64_t rows, int64_t cols) {
  std::string dict = fmt::format("{{'descr': '{}', 'fortran_order': False, 'shape': ({}, {}), }}", npy_descr<T>(),
                                 rows, cols);
  const size_t unpadded = 10 + dict.size() + 1;
  dict.append((64 - unpadded % 64) % 64, ' ');
  dict.push_back('\n');
  std::string bytes("\x93NUMPY\x01\x00", 8);
  const auto hl = static_cast<uint16_t>(dict.size());
  bytes.push_back(static_cast<char>(hl & 0xff));
  bytes.push_back(static_cast<char>(hl >> 8));
  bytes += dict;
  bytes.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  write_file_atomic(path, bytes);
}

// The contact series of every stage, experiment to DEM exact (compare/fabric.hpp).
void write_contact_tables(const fs::path& out, const ReportData& d) {
  const Report& rep = *d.report;
  fs::create_directories(out / "contacts");
  RowTable fab({"stage", "series", "n_contacts", "N_zz", "N_yy", "N_xx", "N_zy", "N_zx", "N_yx", "anisotropy",
                "near_axis_share", "major_axis_tilt_deg"});
  RowTable nor({"stage", "series", "band", "theta_from_deg", "theta_to_deg", "contacts", "density"});
  RowTable size({"stage", "series", "size_class", "d_eq_from_mm", "d_eq_to_mm", "particles", "coordination_mean"});
  for (size_t n = 0; n < rep.stages.size(); ++n) {
    const std::string& st = rep.stages[n].name;
    for (int k = 0; k < 4; ++k) {
      const ContactSeries* c = k < 3 ? (d.series[n][static_cast<size_t>(k)] ? &d.series[n][static_cast<size_t>(k)]->contacts
                                                                              : nullptr)
                                     : d.exact[n];
      if (!c) continue;
      const char* series = k < 3 ? kSeriesNames[k] : kExactSeriesName;
      for (size_t q = 0; q < c->by_size.size(); ++q) {
        const measure::SizeClass& b = c->by_size[q];
        size.row({st, series, q + 1, b.size_from, b.size_to, b.particles, b.mean_coordination});
      }
      if (!c->measured) continue;  // a particle-table input: no contacts
      const measure::Fabric& f = c->fabric;
      fab.row({st, series, f.contacts, f.N(0, 0), f.N(1, 1), f.N(2, 2), f.N(0, 1), f.N(0, 2), f.N(1, 2), f.anisotropy,
               c->near_axis_share, measure::polar_angle_deg(f.major_axis)});
      const measure::PolarHistogram& h = c->polar;
      for (size_t q = 0; q < h.count.size(); ++q)
        nor.row({st, series, q + 1, h.edges_deg[q], h.edges_deg[q + 1], h.count[q], h.density[q]});
      write_csv(c->contacts, out / "contacts" / ("stage" + std::to_string(n) + "_" + series + ".csv"));
    }
  }
  write_csv(fab.table(), out / "fabric.csv");
  write_csv(nor.table(), out / "normals.csv");
  write_csv(size.table(), out / "coordination_by_size.csv");
}

}  // namespace

template <class T>
void write_mid_slices(const Volume<T>& v, const fs::path& dir, const std::string& stem) {
  const Shape s = v.shape();
  const int64_t k0 = s.nz / 2, j0 = s.ny / 2, i0 = s.nx / 2;
  std::vector<T> a;
  for (int64_t j = 0; j < s.ny; ++j)
    for (int64_t i = 0; i < s.nx; ++i) a.push_back(v(k0, j, i));
  write_npy(dir / (stem + "_z.npy"), a, s.ny, s.nx);
  a.clear();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t i = 0; i < s.nx; ++i) a.push_back(v(k, j0, i));
  write_npy(dir / (stem + "_y.npy"), a, s.nz, s.nx);
  a.clear();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j) a.push_back(v(k, j, i0));
  write_npy(dir / (stem + "_x.npy"), a, s.nz, s.ny);
}
template void write_mid_slices(const Volume<uint16_t>&, const fs::path&, const std::string&);
template void write_mid_slices(const Volume<uint32_t>&, const fs::path&, const std::string&);

void write_report_tables(const fs::path& out, const ReportData& d) {
  const Report& rep = *d.report;
  const auto& sv = rep.sieves_mm;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto fr_names = measure::class_labels(measure::fr_thresholds());
  const auto ar_names = measure::class_labels(measure::ar_thresholds());
  RowTable sum({"stage", "series", "axial_strain", "particles", "d10_mm", "d50_mm", "d60_mm", "cu", "hardin_br",
                "broken_fraction", "broken_method", "coordination_interior"});
  RowTable psd({"stage", "series", "sieve_mm", "passing_pct"});
  RowTable cls({"stage", "series", "metric", "class", "percent"});
  // grains_broken / bonds_broken: the DEM history's counts (the study's Fig. 10); NaN on the per-stage rows.
  RowTable broken({"series", "axial_strain", "broken_fraction", "grains_broken", "bonds_broken"});
  for (size_t n = 0; n < rep.stages.size(); ++n)
    for (int k = 0; k < 3; ++k) {
      if (!d.series[n][static_cast<size_t>(k)]) continue;
      const Series& s = *d.series[n][static_cast<size_t>(k)];
      const std::string& st = rep.stages[n].name;
      const char* series = kSeriesNames[k];
      const double e = k == 0 ? rep.stages[n].xct_strain : rep.stages[n].dem_strain;
      const measure::StageGrading& m = s.metrics;
      sum.row({st, series, e, m.particles, m.d.d10, m.d.d50, m.d.d60, m.d.cu, m.hardin_br, s.broken_fraction,
               s.broken_method, s.coordination});
      for (size_t q = 0; q < sv.size(); ++q) psd.row({st, series, sv[q], m.passing[q]});
      for (size_t q = 0; q < m.fr_classes.size(); ++q) cls.row({st, series, "fr", fr_names[q], m.fr_classes[q]});
      for (size_t q = 0; q < m.ar_classes.size(); ++q) cls.row({st, series, "ar", ar_names[q], m.ar_classes[q]});
      if (k != 2) broken.row({k == 0 ? "experiment" : "dem", e, s.broken_fraction, nan, nan});  // one point per stage
    }
  write_csv(sum.table(), out / "summary.csv");
  write_csv(psd.table(), out / "psd.csv");
  // The DEM's particles straight from its spheres: every one, however small (dem_stage.hpp).
  for (size_t n = 0; n < rep.stages.size() && n < d.exact_shapes.size(); ++n) {
    const measure::GradingSample* e = d.exact_shapes[n];
    if (!e || e->fr.empty()) continue;
    const auto fr = measure::class_percent(e->fr, measure::fr_thresholds());
    const auto ar = measure::class_percent(e->ar, measure::ar_thresholds());
    for (size_t q = 0; q < fr.size(); ++q) cls.row({rep.stages[n].name, kExactSeriesName, "fr", fr_names[q], fr[q]});
    for (size_t q = 0; q < ar.size(); ++q) cls.row({rep.stages[n].name, kExactSeriesName, "ar", ar_names[q], ar[q]});
  }
  write_csv(cls.table(), out / "shape_classes.csv");

  RowTable dist({"stage", "pair", "psd_ks", "psd_w1_mm", "fr_ks", "fr_w1", "ar_ks", "ar_w1"});
  for (const StageReport& st : rep.stages) {
    const std::pair<const char*, const Distances*> pairs[3] = {{"experiment_vs_dem_imaged", &st.exp_vs_imaged},
                                                               {"experiment_vs_dem_ideal", &st.exp_vs_ideal},
                                                               {"dem_ideal_vs_dem_imaged", &st.ideal_vs_imaged}};
    for (const auto& [name, ds] : pairs)
      dist.row({st.name, name, ds->psd_ks, ds->psd_w1_mm, ds->fr_ks, ds->fr_w1, ds->ar_ks, ds->ar_w1});
  }
  write_csv(dist.table(), out / "distances.csv");

  RowTable ss({"series", "axial_strain", "stress_mpa"});
  const Curve& hist = d.history;
  for (size_t q = 0; q < hist.strain.size(); ++q) {
    ss.row({"dem", hist.strain[q], hist.stress_mpa[q]});
    if (!hist.broken.empty())
      broken.row({"dem_history", hist.strain[q], hist.broken[q] / static_cast<double>(d.initial_dem_particles),
                  hist.broken[q], hist.bonds.empty() ? nan : hist.bonds[q]});
  }
  for (size_t q = 0; q < d.experiment_curve.strain.size(); ++q)
    ss.row({"experiment", d.experiment_curve.strain[q], d.experiment_curve.stress_mpa[q]});
  write_csv(ss.table(), out / "stress_strain.csv");
  write_csv(broken.table(), out / "broken.csv");
  write_contact_tables(out, d);
  write_lineage_tables(out, rep);
}

namespace {
// The bias as (stage, quantity, value, count) rows: one place for the CSV and report.json.
struct BiasRow {
  std::string stage, quantity;
  double value;
  int64_t count;
};
std::vector<BiasRow> bias_rows(const Report& rep) {
  std::vector<BiasRow> out;
  const track::Accuracy& a = *rep.tracker_bias;
  out.push_back({"all", "right_parent", a.parent_fraction(), a.particles});
  out.push_back({"all", "right_grain", a.grain_fraction(), a.particles});
  for (const auto& [type, sc] : a.events) {
    out.push_back({"all", type + "_recall", sc.recall(), sc.truth});
    out.push_back({"all", type + "_precision", sc.precision(), sc.tracked});
  }
  for (size_t n = 0; n < a.pct_broken.size() && n < rep.stages.size(); ++n) {
    out.push_back({rep.stages[n].name, "pct_intact_broken_exact", a.pct_broken_truth[n], 0});
    out.push_back({rep.stages[n].name, "pct_intact_broken_tracked", a.pct_broken[n], 0});
    out.push_back({rep.stages[n].name, "pct_intact_broken_difference", a.pct_broken[n] - a.pct_broken_truth[n], 0});
  }
  return out;
}
}  // namespace

void write_lineage_tables(const fs::path& out, const Report& rep) {
  std::vector<std::string> cols{"stage", "series", "particles", "grains_intact", "grains_broken", "pct_intact_broken",
                                "split", "fragmentation", "chipping", "chips", "lost", "new"};
  for (int b = 1; b <= 5; ++b) cols.push_back("breaks_band" + std::to_string(b));
  for (int b = 1; b <= 5; ++b) cols.push_back("pct_broken_band" + std::to_string(b));
  RowTable t(cols);
  const std::pair<const char*, const std::optional<track::TrackResult>*> series[3] = {
      {"experiment", &rep.tracking}, {"dem_exact", &rep.dem_exact}, {"dem_imaged", &rep.dem_imaged}};
  bool any = false;
  for (size_t n = 0; n < rep.stages.size(); ++n)
    for (const auto& [name, r] : series) {
      if (!*r || n >= (**r).summary.size()) continue;
      const track::SummaryRow& s = (**r).summary[n];
      const auto& bb = s.breaks_band;
      const auto& pb = s.pct_broken_band;
      t.row({rep.stages[n].name, name, s.particles, s.grains_intact, s.grains_broken, s.pct_intact_broken, s.split,
             s.fragmentation, s.chipping, s.chips, s.lost, s.new_particles, bb[0], bb[1], bb[2], bb[3], bb[4], pb[0], pb[1],
             pb[2], pb[3], pb[4]});
      any = true;
    }
  if (any) write_csv(t.table(), out / "lineage.csv");
  if (!rep.tracker_bias) return;
  RowTable b({"stage", "quantity", "value", "count"});
  for (const BiasRow& r : bias_rows(rep)) b.row({r.stage, r.quantity, r.value, r.count});
  write_csv(b.table(), out / "tracker_bias.csv");
}

json lineage_json(const Report& rep) {
  json j;
  j["dem_exact"] = rep.dem_exact ? json("dem_lineage/ (lineage.csv, events.csv, summary.csv)") : json(nullptr);
  j["dem_imaged"] = rep.dem_imaged ? json("dem_imaged_tracking/ (lineage.csv, events.csv, summary.csv)") : json(nullptr);
  j["note"] = rep.dem_lineage_note;
  if (rep.tracker_bias) {
    json b = json::array();
    for (const BiasRow& r : bias_rows(rep)) b.push_back({{"stage", r.stage}, {"quantity", r.quantity}, {"value", r.value}, {"count", r.count}});
    j["tracker_bias"] = b;
  }
  return j;
}

void write_report_json(const fs::path& out, const ReportData& d, json meta) {
  const Report& rep = *d.report;
  meta["stages"] = json::array();
  for (size_t n = 0; n < rep.stages.size(); ++n) {
    const StageReport& st = rep.stages[n];
    const Series& x = *d.series[n][0];
    json j;
    j["index"] = n;
    j["name"] = st.name;
    j["slices"] = "stage" + std::to_string(n);
    j["experiment"] = {{"source", st.xct_source}, {"strain", num(st.xct_strain)}, {"synthetic", st.synthetic},
                       {"particles", st.n_experiment}, {"info", x.info}};
    if (const GreyEstimate* g = d.grey[n])
      j["experiment"]["grey_estimate"] = {{"void_grey", g->void_grey},
                                          {"solid_grey", g->solid_grey},
                                          {"noise_sigma", g->noise_sigma},
                                          {"otsu_threshold", g->threshold},
                                          {"method", g->method}};
    const json none = json::object();
    j["dem"] = {{"snapshot", st.dem_snapshot},
                {"strain", num(st.dem_strain)},
                {"particles_ideal", st.n_ideal},
                {"particles_imaged", st.n_imaged},
                {"ideal", d.series[n][1]->info},
                {"imaged", d.series[n][2] ? d.series[n][2]->info : none}};
    j["distances"] = {{"experiment_vs_dem_imaged", distances_json(st.exp_vs_imaged)},
                      {"experiment_vs_dem_ideal", distances_json(st.exp_vs_ideal)},
                      {"dem_ideal_vs_dem_imaged", distances_json(st.ideal_vs_imaged)}};
    j["seconds"] = st.seconds;
    j["peak_rss_bytes"] = st.peak_rss_bytes;
    j["peak_rss_bytes_per_voxel"] = st.voxels ? json(double(st.peak_rss_bytes) / double(st.voxels)) : json(nullptr);
    j["peak_scope"] = st.own_peak ? "stage" : "process";
    meta["stages"].push_back(j);
  }
  meta["sieves_mm"] = rep.sieves_mm;
  meta["fr_classes"] = measure::class_labels(measure::fr_thresholds());
  meta["ar_classes"] = measure::class_labels(measure::ar_thresholds());
  meta["has_experimental_curve"] = !d.experiment_curve.strain.empty();
  meta["has_history"] = !d.history.strain.empty();
  meta["history_stress_column"] = d.history.stress_column;
  meta["initial_dem_particles"] = d.initial_dem_particles;
  write_file_atomic(out / "report.json", meta.dump(2) + "\n");
}

fs::path run_plot_script(const fs::path& out, const std::string& python, const std::string& script_opt) {
  fs::path script = script_opt;
  if (script.empty()) {
    const char* e = std::getenv("TOMOGRAIN_REPORT_SCRIPT");
    script = e && *e ? fs::path(e) : fs::path(TOMOGRAIN_REPORT_SCRIPT);
  }
  if (script.empty() || !fs::exists(script))
    throw ResourceError("compare: report script not found (" + script.string() +
                        "); set TOMOGRAIN_REPORT_SCRIPT to compare/report/make_report.py");
  const auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  const std::string cmd = quote(python) + " " + quote(script.string()) + " " + quote(out.string());
  const int rc = std::system(cmd.c_str());
  if (rc != 0)
    throw ResourceError("compare: the report script failed (" + cmd + ", status " + std::to_string(rc) +
                        "); it needs Debian's python3-matplotlib and python3-numpy. The CSV/JSON data are in " +
                        out.string());
  return out / "index.html";
}

}  // namespace tg::compare

#include "compare/comparison.hpp"
#include "core/natural_order.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "measure/psd.hpp"

#ifndef TOMOGRAIN_REPORT_SCRIPT
#define TOMOGRAIN_REPORT_SCRIPT ""
#endif

namespace tg::compare {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

bool is_h5(const fs::path& p) { return p.extension() == ".h5" || p.extension() == ".hdf5"; }

// JSON has no NaN: null instead.
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// ------------------------------------------------------------ .npy slices

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
  std::ofstream f(path, std::ios::binary);
  if (!f) throw InputError(path.string() + ": cannot write");
  f.write("\x93NUMPY\x01\x00", 8);
  const auto hl = static_cast<uint16_t>(dict.size());
  const char hb[2] = {static_cast<char>(hl & 0xff), static_cast<char>(hl >> 8)};
  f.write(hb, 2);
  f.write(dict.data(), static_cast<std::streamsize>(dict.size()));
  f.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(T)));
  if (!f) throw InputError(path.string() + ": write failed");
}

// The three orthogonal mid-slices (z: ny×nx, y: nz×nx, x: nz×ny) of a volume.
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

// ------------------------------------------------------------ tables

// First column present among `names`, or -1.
std::string first_of(const Table& t, std::initializer_list<const char*> names) {
  for (const char* n : names)
    if (t.has(n) && !t.columns()[static_cast<size_t>(t.find(n))].is_text) return n;
  return "";
}

// Axial stress in MPa from a history/curve table: the first known stress column,
// unit from its suffix.
struct Curve {
  std::vector<double> strain, stress_mpa, broken;  // broken empty when absent
  std::string stress_column;
};
Curve read_curve(const fs::path& path) {
  Table t = read_csv(path);
  Curve c;
  const std::string e = first_of(t, {"axial_strain", "strain", "eps_zz", "strain_zz"});
  if (e.empty()) throw InputError(path.string() + ": no strain column (axial_strain or strain)");
  std::string s = first_of(t, {"axial_stress_Pa", "stress_zz_Pa", "sigma_zz_Pa", "top_stress_Pa", "stress_Pa",
                               "axial_stress_kPa", "stress_kPa", "axial_stress_MPa", "stress_MPa"});
  if (s.empty())
    for (const Column& col : t.columns())
      if (!col.is_text && col.name.find("stress") != std::string::npos) {
        s = col.name;
        break;
      }
  if (s.empty()) throw InputError(path.string() + ": no axial stress column (e.g. axial_stress_Pa)");
  double scale = 1e-6;  // Pa -> MPa (also for unitless names)
  if (s.ends_with("kPa")) scale = 1e-3;
  if (s.ends_with("MPa")) scale = 1;
  c.stress_column = s;
  c.strain = t.num(e);
  for (double v : t.num(s)) c.stress_mpa.push_back(v * scale);
  const std::string b = first_of(t, {"grains_broken", "broken_grains", "broken_particles", "broken"});
  if (!b.empty()) c.broken = t.num(b);
  return c;
}

double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  if (x.empty()) return kNaN;
  size_t best = 0;
  for (size_t q = 1; q < x.size(); ++q)
    if (std::abs(x[q] - at) < std::abs(x[best] - at)) best = q;
  // Linear between the bracketing rows when x is ascending there, else the nearest row.
  for (size_t q = 1; q < x.size(); ++q)
    if (x[q - 1] <= at && at <= x[q] && x[q] > x[q - 1])
      return y[q - 1] + (y[q] - y[q - 1]) * (at - x[q - 1]) / (x[q] - x[q - 1]);
  return y[best];
}

std::vector<std::string> find_snapshots(const fs::path& run) {
  fs::path dir = fs::is_directory(run / "snapshots") ? run / "snapshots" : run;
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const auto name = e.path().filename().string();
    if (name == "history.csv" || name == "snapshots.csv") continue;
    if (is_h5(e.path())) out.push_back(e.path().string());
    if (e.path().extension() == ".csv") {
      // Only sphere tables: the DEM also writes other CSVs beside snapshots (bonds).
      std::ifstream f(e.path());
      std::string header;
      std::getline(f, header);
      if (header.find("x_m") != std::string::npos && header.find("r_m") != std::string::npos)
        out.push_back(e.path().string());
    }
  }
  std::sort(out.begin(), out.end(), tg::natural_less);
  if (out.empty()) throw InputError(run.string() + ": no DEM snapshots (*.csv or *.h5 in snapshots/ or the run folder)");
  return out;
}

// A snapshot's strain from its own file: the DEM snapshot attribute (JSON "strain"),
// an HDF5 attribute axial_strain, or a CSV column axial_strain/strain.
double snapshot_strain(const std::string& path) {
  if (is_h5(path)) {
    H5Reader rd(path);
    // dem/snapshot.hpp: root attribute "snapshot" = JSON with "strain".
    const json j = json::parse(rd.read_attribute("snapshot"), nullptr, false);
    if (j.is_object() && j.contains("strain") && j["strain"].is_number()) return j["strain"].get<double>();
    const std::string a = rd.read_attribute("axial_strain");
    if (!a.empty()) {
      try {
        return std::stod(a);
      } catch (const std::exception&) {
        throw InputError(path + ": attribute axial_strain is not a number");
      }
    }
    return kNaN;
  }
  Table t = read_csv(path);
  const std::string e = first_of(t, {"axial_strain", "strain"});
  return e.empty() || t.rows() == 0 ? kNaN : t.num(e)[0];
}

// ------------------------------------------------------------ one series

struct Series {
  StageSample sample;
  Table particles;
  StageMetrics metrics;
  double broken_fraction = kNaN;
  std::string broken_method;
  json info = json::object();
};

Table measure_labels(const Volume<uint32_t>& labels, const measure::ParticleOptions& po) {
  return measure::particle_table(measure::measure_particles(labels.view(), po));
}

// Fraction of the initial grains that are broken, from a data_synth truth table:
// distinct parents of fragment rows over distinct parents of all rows.
double broken_from_truth(const Table& truth) {
  if (!truth.has("kind") || !truth.has("parent")) return kNaN;
  const auto& kind = truth.text("kind");
  const auto& parent = truth.num("parent");
  std::map<double, bool> broken;
  for (int64_t q = 0; q < truth.rows(); ++q) {
    auto [it, fresh] = broken.try_emplace(parent[q], false);
    if (kind[q] != "grain") it->second = true;
  }
  int64_t n = 0;
  for (const auto& [p, b] : broken) n += b;
  return broken.empty() ? kNaN : static_cast<double>(n) / static_cast<double>(broken.size());
}

struct XctStage {
  Series s;
  double strain = kNaN;
  bool synthetic = false;
  Geometry geometry;  // voxel size unknown (0) for particle-table inputs
  std::optional<GreyEstimate> grey;
};

// The segmentation options both worlds share at one voxel size: the scale is
// the option, else the first snapshot's median particle radius in voxels.
SegmentOptions segment_options(const CompareOptions& opt, double median_r_m, double voxel_m) {
  SegmentOptions so = opt.segment;
  so.grain_radius_vox = opt.grain_radius_vox > 0 ? opt.grain_radius_vox : median_r_m / voxel_m;
  return so;
}

XctStage load_xct(const std::string& path, const CompareOptions& opt, double median_r_m, const fs::path& slices,
                  const std::string& stem) {
  XctStage x;
  x.synthetic = opt.synthetic_xct;
  if (fs::path(path).extension() == ".csv") {
    x.s.particles = read_csv(path, {"d_med_mm", "volume_mm3", "fr", "ar"});
    x.s.info["input"] = "particle table";
  } else {
    const auto [file, ds] = split_dataset_spec(path);
    ReadOptions ro;
    ro.progress = false;
    Volume<uint16_t> grey;
    Volume<uint32_t> labels;
    if (is_h5(file)) {
      H5Reader rd(file);
      const std::string prov = rd.read_attribute("synth");
      if (!prov.empty()) {
        x.synthetic = true;
        const json j = json::parse(prov, nullptr, false);
        if (j.is_object() && j.contains("axial_strain") && j["axial_strain"].is_number())
          x.strain = j["axial_strain"].get<double>();
        x.s.info["provenance"] = j.is_discarded() ? json(prov) : j;
      }
      if (rd.has("/truth")) {
        x.s.broken_fraction = broken_from_truth(rd.read_table("/truth"));
        if (std::isfinite(x.s.broken_fraction)) x.s.broken_method = "synthetic truth (grains with fragments)";
      }
      const bool want_grey = !ds.empty() ? ds != "/labels" : rd.has("/volume");
      if (want_grey)
        grey = read_volume_as<uint16_t>(ds.empty() ? file + ":/volume" : path, ro);
      else
        labels = read_volume_as<uint32_t>(ds.empty() ? file + ":/labels" : path, ro);
    } else {
      grey = read_volume_as<uint16_t>(path, ro);
    }
    x.geometry = grey.empty() ? labels.geometry() : grey.geometry();
    if (!x.geometry.has_voxel_size() || !x.geometry.isotropic())
      throw InputError(path + ": needs an isotropic voxel size in the file");
    if (!grey.empty()) {
      x.grey = estimate_grey_levels(grey);
      const SegmentOptions so = segment_options(opt, median_r_m, x.geometry.voxel_size_m[0]);
      write_mid_slices(grey, slices, stem + "_experiment_grey");
      SegmentResult r = segment(std::move(grey), so);
      x.s.info["input"] = "grey scan, segmented";
      x.s.info["segment"] = json::parse(summary_json(r, so), nullptr, false);
      labels = std::move(r.labels);
    } else {
      x.s.info["input"] = "label volume";
    }
    write_mid_slices(labels, slices, stem + "_experiment_labels");
    x.s.particles = measure_labels(labels, opt.measure);
  }
  x.s.particles.source = path;
  x.s.sample = sample_from_table(x.s.particles);
  return x;
}

const char* kSeries[3] = {"experiment", "dem_ideal", "dem_imaged"};

fs::path default_script() {
  if (const char* e = std::getenv("TOMOGRAIN_REPORT_SCRIPT"); e && *e) return e;
  return TOMOGRAIN_REPORT_SCRIPT;
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

json distances_json(const Distances& d) {
  return {{"psd_ks", num(d.psd_ks)}, {"psd_w1_mm", num(d.psd_w1_mm)}, {"fr_ks", num(d.fr_ks)},
          {"fr_w1", num(d.fr_w1)},   {"ar_ks", num(d.ar_ks)},         {"ar_w1", num(d.ar_w1)}};
}

}  // namespace

Report run_comparison(const CompareInputs& in, const CompareOptions& opt) {
  const auto t_all = std::chrono::steady_clock::now();
  if (in.xct.empty()) throw UsageError("compare: give at least one XCT stage (--xct)");
  if (in.dem_run.empty() && in.dem_snapshots.empty()) throw UsageError("compare: give a DEM run folder (--dem)");
  if (in.report_dir.empty()) throw UsageError("compare: give the report folder (-o)");
  if (!in.xct_strains.empty() && in.xct_strains.size() != in.xct.size())
    throw UsageError("compare: give one XCT strain per stage (" + std::to_string(in.xct.size()) + ")");
  if (!in.stage_names.empty() && in.stage_names.size() != in.xct.size())
    throw UsageError("compare: give one stage name per XCT stage");
  const fs::path run(in.dem_run);
  if (!in.dem_run.empty() && !fs::is_directory(run)) throw InputError(in.dem_run + ": not a folder (DEM run)");

  // DEM snapshots and their strains.
  const std::vector<std::string> snaps = in.dem_snapshots.empty() ? find_snapshots(run) : in.dem_snapshots;
  std::vector<double> snap_strain(snaps.size(), kNaN);
  if (!in.dem_strains.empty()) {
    if (in.dem_strains.size() != snaps.size())
      throw UsageError("compare: " + std::to_string(snaps.size()) + " DEM snapshots but " +
                       std::to_string(in.dem_strains.size()) + " strains");
    snap_strain = in.dem_strains;
  } else if (!in.dem_run.empty() && fs::exists(run / "snapshots.csv")) {
    Table idx = read_csv(run / "snapshots.csv");
    const std::string e = first_of(idx, {"axial_strain", "strain"});
    if (e.empty() || !idx.has("file"))
      throw InputError((run / "snapshots.csv").string() + ": need columns file, axial_strain");
    const auto& files = idx.text("file");
    for (size_t n = 0; n < snaps.size(); ++n)
      for (int64_t q = 0; q < idx.rows(); ++q)
        if (fs::path(snaps[n]).filename() == fs::path(files[static_cast<size_t>(q)]).filename())
          snap_strain[n] = idx.num(e)[static_cast<size_t>(q)];
  } else {
    for (size_t n = 0; n < snaps.size(); ++n) snap_strain[n] = snapshot_strain(snaps[n]);
  }

  Curve hist, expc;
  const bool has_hist = !in.dem_run.empty() && fs::exists(run / "history.csv");
  if (has_hist) hist = read_curve(run / "history.csv");
  if (!in.experimental_curve.empty()) expc = read_curve(in.experimental_curve);

  const fs::path out(in.report_dir);
  fs::create_directories(out / "slices");
  fs::create_directories(out / "particles");

  // Segmentation scale and the initial grain count from the first snapshot.
  double median_r_m = 0;
  int64_t n0_particles = 0;
  {
    const SphereTable first = read_spheres(snaps.front());
    std::map<int64_t, double> vol;
    for (size_t q = 0; q < first.size(); ++q) vol[first.particle[q]] += std::pow(first.r_m[q], 3);
    std::vector<double> r;
    for (const auto& [id, v] : vol) r.push_back(std::cbrt(v));  // equal-volume sphere radius
    std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2), r.end());
    median_r_m = r[r.size() / 2];
    n0_particles = static_cast<int64_t>(vol.size());
  }

  Report rep;
  rep.dir = out;
  json meta;
  meta["title"] = in.title;
  meta["notes"] = in.notes;
  meta["dem_run"] = in.dem_run;
  meta["dem_snapshots"] = snaps;
  meta["sizing"] = measure::sizing_name(opt.measure);
  meta["imaged_path"] = opt.imaged_path;
  meta["stages"] = json::array();

  std::vector<XctStage> xs;
  std::vector<Series> ideal(in.xct.size()), imaged(in.xct.size());
  for (size_t n = 0; n < in.xct.size(); ++n) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::string stem = "stage" + std::to_string(n);
    XctStage x = load_xct(in.xct[n], opt, median_r_m, out / "slices", stem);
    if (!in.xct_strains.empty()) x.strain = in.xct_strains[n];

    // Match a snapshot: nearest strain when both are known, else by order.
    size_t m = std::min(n, snaps.size() - 1);
    if (std::isfinite(x.strain)) {
      double best = std::numeric_limits<double>::max();
      for (size_t q = 0; q < snaps.size(); ++q)
        if (std::isfinite(snap_strain[q]) && std::abs(snap_strain[q] - x.strain) < best) {
          best = std::abs(snap_strain[q] - x.strain);
          m = q;
        }
    }
    const double vox_m = opt.voxel_um > 0 ? opt.voxel_um * 1e-6 : x.geometry.voxel_size_m[0];
    if (!(vox_m > 0)) throw UsageError("compare: " + in.xct[n] + " has no voxel size: give --voxel-um");

    VoxeliseOptions vo = opt.voxelise;
    vo.voxel_m = vox_m;
    vo.grey = opt.imaged_path;
    if (opt.like_scan && x.grey) vo.imaging = imaging_like(*x.grey, vo.imaging);
    Voxelised v = voxelise(read_spheres(snaps[m]), vo);
    const SegmentOptions so = segment_options(opt, median_r_m, vox_m);

    Series& id = ideal[n];
    id.particles = measure_labels(v.labels, opt.measure);
    id.sample = sample_from_table(id.particles);
    write_mid_slices(v.labels, out / "slices", stem + "_dem_ideal_labels");
    Series& im = imaged[n];
    if (opt.imaged_path) {
      write_mid_slices(v.grey, out / "slices", stem + "_dem_grey");
      SegmentResult r = segment(std::move(v.grey), so);
      im.info["segment"] = json::parse(summary_json(r, so), nullptr, false);
      write_mid_slices(r.labels, out / "slices", stem + "_dem_imaged_labels");
      im.particles = measure_labels(r.labels, opt.measure);
      im.sample = sample_from_table(im.particles);
    }
    // Broken grains of the DEM: history's count at this strain over the initial
    // particles, else the growth of the particle count (each break adds one).
    const double e_dem = snap_strain[m];
    double bf = kNaN;
    std::string bm;
    if (has_hist && !hist.broken.empty() && std::isfinite(e_dem)) {
      bf = interpolate(hist.strain, hist.broken, e_dem) / static_cast<double>(n0_particles);
      bm = "history.csv broken grains / initial particles";
    } else {
      const int64_t np = static_cast<int64_t>(v.particle_of_label.size()) - 1;
      bf = std::clamp(static_cast<double>(np - n0_particles) / static_cast<double>(n0_particles), 0.0, 1.0);
      bm = "particle count growth (one extra particle per break)";
    }
    id.broken_fraction = im.broken_fraction = bf;
    id.broken_method = im.broken_method = bm;
    id.info["voxelise"] = {{"snapshot", snaps[m]},
                           {"voxel_um", vox_m * 1e6},
                           {"shape", {v.labels.shape().nz, v.labels.shape().ny, v.labels.shape().nx}},
                           {"solid_fraction", v.solid_fraction},
                           {"render_s", v.render_s},
                           {"imaging_s", v.imaging_s},
                           {"void_grey", vo.imaging.void_grey},
                           {"solid_grey", vo.imaging.solid_grey},
                           {"noise_sigma", vo.imaging.noise_sigma},
                           {"psf_sigma_vox", vo.imaging.psf_sigma},
                           {"imaging_from",
                            opt.like_scan && x.grey ? "estimated from the XCT scan: " + x.grey->method : "defaults"}};

    StageReport st;
    st.name = !in.stage_names.empty() ? in.stage_names[n]
                                      : fmt::format("stage {}{}", n,
                                                    std::isfinite(x.strain) ? fmt::format(" (strain {:.2f} %)", 100 * x.strain) : "");
    st.xct_strain = x.strain;
    st.dem_strain = e_dem;
    st.xct_source = in.xct[n];
    st.dem_snapshot = snaps[m];
    st.synthetic = x.synthetic;
    st.n_experiment = static_cast<int64_t>(x.s.sample.dmed_mm.size());
    st.n_ideal = static_cast<int64_t>(id.sample.dmed_mm.size());
    st.n_imaged = static_cast<int64_t>(im.sample.dmed_mm.size());
    st.exp_vs_ideal = sample_distances(x.s.sample, id.sample);
    st.exp_vs_imaged = sample_distances(x.s.sample, im.sample);
    st.ideal_vs_imaged = sample_distances(id.sample, im.sample);
    st.seconds = seconds_since(t0);
    rep.stages.push_back(st);
    xs.push_back(std::move(x));
    write_csv(xs.back().s.particles, out / "particles" / (stem + "_experiment.csv"));
    write_csv(id.particles, out / "particles" / (stem + "_dem_ideal.csv"));
    if (opt.imaged_path) write_csv(im.particles, out / "particles" / (stem + "_dem_imaged.csv"));
  }

  // Sieves common to every series, then the metrics and Br against each series' first stage.
  std::vector<const StageSample*> all;
  for (size_t n = 0; n < xs.size(); ++n) {
    all.push_back(&xs[n].s.sample);
    all.push_back(&ideal[n].sample);
    if (opt.imaged_path) all.push_back(&imaged[n].sample);
  }
  rep.sieves_mm = sieves_for(all);
  const auto& sv = rep.sieves_mm;
  auto series_of = [&](size_t n, int k) -> Series& { return k == 0 ? xs[n].s : k == 1 ? ideal[n] : imaged[n]; };
  const int nseries = opt.imaged_path ? 3 : 2;
  for (int k = 0; k < nseries; ++k)
    for (size_t n = 0; n < xs.size(); ++n) {
      Series& s = series_of(n, k);
      s.metrics = stage_metrics(s.sample, sv);
      const Series& s0 = series_of(0, k);
      s.metrics.hardin_br = s.sample.dmed_mm.empty() || s0.sample.dmed_mm.empty()
                                ? kNaN
                                : measure::hardin_br(sv, s0.metrics.passing, s.metrics.passing);
    }
  for (size_t n = 0; n < xs.size(); ++n) {
    rep.stages[n].experiment = xs[n].s.metrics;
    rep.stages[n].ideal = ideal[n].metrics;
    rep.stages[n].imaged = imaged[n].metrics;
  }
  // Experimental broken fraction without truth: particle count growth against stage 0.
  for (size_t n = 0; n < xs.size(); ++n)
    if (!std::isfinite(xs[n].s.broken_fraction)) {
      const double n0 = static_cast<double>(xs[0].s.sample.dmed_mm.size());
      xs[n].s.broken_fraction =
          n0 > 0 ? std::clamp((static_cast<double>(xs[n].s.sample.dmed_mm.size()) - n0) / n0, 0.0, 1.0) : kNaN;
      xs[n].s.broken_method = "particle count growth against stage 0 (one extra particle per break)";
    }

  // ---- the numbers behind the plots
  {
    std::vector<std::string> c_stage, c_series, c_method;
    std::vector<double> c_strain, c_n, c_d10, c_d50, c_d60, c_cu, c_br, c_bf;
    std::vector<std::string> p_stage, p_series;
    std::vector<double> p_sieve, p_pass;
    std::vector<std::string> h_stage, h_series, h_metric, h_class;
    std::vector<double> h_pct;
    std::vector<std::string> b_series;
    std::vector<double> b_strain, b_frac;
    const char* fr_names[4] = {"<0.4", "0.4-0.8", "0.8-0.9", ">=0.9"};
    const char* ar_names[3] = {"<2", "2-3", ">=3"};
    for (size_t n = 0; n < xs.size(); ++n)
      for (int k = 0; k < nseries; ++k) {
        const Series& s = series_of(n, k);
        const std::string& st = rep.stages[n].name;
        const double e = k == 0 ? rep.stages[n].xct_strain : rep.stages[n].dem_strain;
        c_stage.push_back(st);
        c_series.push_back(kSeries[k]);
        c_method.push_back(s.broken_method);
        c_strain.push_back(e);
        c_n.push_back(static_cast<double>(s.metrics.particles));
        c_d10.push_back(s.metrics.d10);
        c_d50.push_back(s.metrics.d50);
        c_d60.push_back(s.metrics.d60);
        c_cu.push_back(s.metrics.cu);
        c_br.push_back(s.metrics.hardin_br);
        c_bf.push_back(s.broken_fraction);
        for (size_t q = 0; q < sv.size(); ++q) {
          p_stage.push_back(st);
          p_series.push_back(kSeries[k]);
          p_sieve.push_back(sv[q]);
          p_pass.push_back(s.metrics.passing[q]);
        }
        for (size_t q = 0; q < s.metrics.fr_classes.size(); ++q) {
          h_stage.push_back(st);
          h_series.push_back(kSeries[k]);
          h_metric.push_back("fr");
          h_class.push_back(fr_names[q]);
          h_pct.push_back(s.metrics.fr_classes[q]);
        }
        for (size_t q = 0; q < s.metrics.ar_classes.size(); ++q) {
          h_stage.push_back(st);
          h_series.push_back(kSeries[k]);
          h_metric.push_back("ar");
          h_class.push_back(ar_names[q]);
          h_pct.push_back(s.metrics.ar_classes[q]);
        }
        if (k != 2) {  // broken fraction: one point per stage for experiment and DEM
          b_series.push_back(k == 0 ? "experiment" : "dem");
          b_strain.push_back(e);
          b_frac.push_back(s.broken_fraction);
        }
      }
    Table sum;
    sum.add_text("stage", c_stage);
    sum.add_text("series", c_series);
    sum.add("axial_strain", c_strain);
    sum.add("particles", c_n);
    sum.add("d10_mm", c_d10);
    sum.add("d50_mm", c_d50);
    sum.add("d60_mm", c_d60);
    sum.add("cu", c_cu);
    sum.add("hardin_br", c_br);
    sum.add("broken_fraction", c_bf);
    sum.add_text("broken_method", c_method);
    write_csv(sum, out / "summary.csv");
    Table psd;
    psd.add_text("stage", p_stage);
    psd.add_text("series", p_series);
    psd.add("sieve_mm", p_sieve);
    psd.add("passing_pct", p_pass);
    write_csv(psd, out / "psd.csv");
    Table cls;
    cls.add_text("stage", h_stage);
    cls.add_text("series", h_series);
    cls.add_text("metric", h_metric);
    cls.add_text("class", h_class);
    cls.add("percent", h_pct);
    write_csv(cls, out / "shape_classes.csv");

    std::vector<std::string> d_stage, d_pair;
    std::vector<double> d[6];
    for (const StageReport& st : rep.stages) {
      const std::pair<const char*, const Distances*> pairs[3] = {{"experiment_vs_dem_imaged", &st.exp_vs_imaged},
                                                                 {"experiment_vs_dem_ideal", &st.exp_vs_ideal},
                                                                 {"dem_ideal_vs_dem_imaged", &st.ideal_vs_imaged}};
      for (const auto& [name, ds] : pairs) {
        d_stage.push_back(st.name);
        d_pair.push_back(name);
        const double vals[6] = {ds->psd_ks, ds->psd_w1_mm, ds->fr_ks, ds->fr_w1, ds->ar_ks, ds->ar_w1};
        for (int q = 0; q < 6; ++q) d[q].push_back(vals[q]);
      }
    }
    Table dist;
    dist.add_text("stage", d_stage);
    dist.add_text("pair", d_pair);
    const char* dn[6] = {"psd_ks", "psd_w1_mm", "fr_ks", "fr_w1", "ar_ks", "ar_w1"};
    for (int q = 0; q < 6; ++q) dist.add(dn[q], d[q]);
    write_csv(dist, out / "distances.csv");

    std::vector<std::string> s_series;
    std::vector<double> s_strain, s_stress;
    for (size_t q = 0; q < hist.strain.size(); ++q) {
      s_series.push_back("dem");
      s_strain.push_back(hist.strain[q]);
      s_stress.push_back(hist.stress_mpa[q]);
      if (!hist.broken.empty()) {
        b_series.push_back("dem_history");
        b_strain.push_back(hist.strain[q]);
        b_frac.push_back(hist.broken[q] / static_cast<double>(n0_particles));
      }
    }
    for (size_t q = 0; q < expc.strain.size(); ++q) {
      s_series.push_back("experiment");
      s_strain.push_back(expc.strain[q]);
      s_stress.push_back(expc.stress_mpa[q]);
    }
    Table ss;
    ss.add_text("series", s_series);
    ss.add("axial_strain", s_strain);
    ss.add("stress_mpa", s_stress);
    write_csv(ss, out / "stress_strain.csv");
    Table br;
    br.add_text("series", b_series);
    br.add("axial_strain", b_strain);
    br.add("broken_fraction", b_frac);
    write_csv(br, out / "broken.csv");
  }

  for (size_t n = 0; n < rep.stages.size(); ++n) {
    const StageReport& st = rep.stages[n];
    json j;
    j["index"] = n;
    j["name"] = st.name;
    j["slices"] = "stage" + std::to_string(n);
    j["experiment"] = {{"source", st.xct_source}, {"strain", num(st.xct_strain)}, {"synthetic", st.synthetic},
                       {"particles", st.n_experiment}, {"info", xs[n].s.info}};
    if (xs[n].grey)
      j["experiment"]["grey_estimate"] = {{"void_grey", xs[n].grey->void_grey},
                                          {"solid_grey", xs[n].grey->solid_grey},
                                          {"noise_sigma", xs[n].grey->noise_sigma},
                                          {"otsu_threshold", xs[n].grey->threshold},
                                          {"method", xs[n].grey->method}};
    j["dem"] = {{"snapshot", st.dem_snapshot}, {"strain", num(st.dem_strain)}, {"particles_ideal", st.n_ideal},
                {"particles_imaged", st.n_imaged}, {"ideal", ideal[n].info}, {"imaged", imaged[n].info}};
    j["distances"] = {{"experiment_vs_dem_imaged", distances_json(st.exp_vs_imaged)},
                      {"experiment_vs_dem_ideal", distances_json(st.exp_vs_ideal)},
                      {"dem_ideal_vs_dem_imaged", distances_json(st.ideal_vs_imaged)}};
    j["seconds"] = st.seconds;
    meta["stages"].push_back(j);
  }
  meta["sieves_mm"] = rep.sieves_mm;
  meta["has_experimental_curve"] = !expc.strain.empty();
  meta["has_history"] = has_hist;
  meta["history_stress_column"] = hist.stress_column;
  meta["initial_dem_particles"] = n0_particles;
  meta["segmentation_grain_radius_m"] = opt.grain_radius_vox > 0 ? json(nullptr) : json(median_r_m);
  rep.seconds = seconds_since(t_all);
  meta["compute_seconds"] = rep.seconds;
  {
    const fs::path tmp = out / "report.json.tmp";
    std::ofstream f(tmp);
    f << meta.dump(2) << '\n';
    f.close();
    if (!f) throw InputError((out / "report.json").string() + ": write failed");
    fs::rename(tmp, out / "report.json");
  }

  if (opt.plots) {
    const fs::path script = opt.script.empty() ? default_script() : fs::path(opt.script);
    if (script.empty() || !fs::exists(script))
      throw ResourceError("compare: report script not found (" + script.string() +
                          "); set TOMOGRAIN_REPORT_SCRIPT to compare/report/make_report.py");
    const std::string cmd = shell_quote(opt.python) + " " + shell_quote(script.string()) + " " + shell_quote(out.string());
    const int rc = std::system(cmd.c_str());
    if (rc != 0)
      throw ResourceError("compare: the report script failed (" + cmd + ", status " + std::to_string(rc) +
                          "); it needs Debian's python3-matplotlib and python3-numpy. The CSV/JSON data are in " +
                          out.string());
    rep.index_html = out / "index.html";
  }
  rep.seconds = seconds_since(t_all);
  return rep;
}

}  // namespace tg::compare

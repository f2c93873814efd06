#include "compare/xct_stage.hpp"

#include <cmath>
#include <map>

#include "compare/report_files.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"

namespace tg::compare {
namespace fs = std::filesystem;
using json = nlohmann::json;

double broken_from_truth(const Table& truth) {
  if (!truth.has("kind") || !truth.has("parent")) return std::numeric_limits<double>::quiet_NaN();
  const auto& kind = truth.text("kind");
  const auto& parent = truth.num("parent");
  std::map<double, bool> broken;
  for (int64_t q = 0; q < truth.rows(); ++q) {
    auto [it, fresh] = broken.try_emplace(parent[q], false);
    if (kind[q] != "grain") it->second = true;
  }
  int64_t n = 0;
  for (const auto& [p, b] : broken) n += b;
  return broken.empty() ? std::numeric_limits<double>::quiet_NaN()
                        : static_cast<double>(n) / static_cast<double>(broken.size());
}

SegmentOptions segment_options(const CompareOptions& opt, double median_r_m, double voxel_m) {
  SegmentOptions so = opt.segment;
  so.grain_radius_vox = opt.grain_radius_vox > 0 ? opt.grain_radius_vox : median_r_m / voxel_m;
  return so;
}

XctStage load_xct_stage(const std::string& path, const CompareOptions& opt, double median_r_m,
                        const fs::path& slices, const std::string& stem) {
  XctStage x;
  x.synthetic = opt.synthetic_xct;
  if (fs::path(path).extension() == ".csv") {
    x.s.particles = read_csv(path, {"d_med_mm", "volume_mm3", "fr", "ar"});
    x.s.info["input"] = "particle table";
    x.s.sample = measure::grading_sample(x.s.particles);  // no contacts: only the table's own columns
    x.s.coordination = mean_interior_coordination(x.s.particles);
    x.s.contacts.by_size = coordination_by_size(x.s.particles);
  } else {
    const auto [file, ds] = split_dataset_spec(path);
    ReadOptions ro;
    ro.progress = false;
    Volume<uint16_t> grey;
    Volume<uint32_t> labels;
    if (is_hdf5(file)) {
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
        labels = read_label_volume(ds.empty() ? file + ":/labels" : path, ro);
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
      SegmentResult r = segment(grey, so);  // the scan stays for the grey-level volumes
      x.s.info["input"] = "grey scan, segmented";
      x.s.info["segment"] = json::parse(summary_json(r, so), nullptr, false);
      labels = std::move(r.labels);
    } else {
      x.s.info["input"] = "label volume";
    }
    write_mid_slices(labels, slices, stem + "_experiment_labels");
    measure_series(labels, opt.measure, x.s, grey.empty() ? nullptr : &grey);
    if (opt.track && opt.track_rotations) x.scan = std::move(grey);
    grey = Volume<uint16_t>();
    x.labels = std::move(labels);
  }
  x.s.particles.source = path;
  return x;
}

}  // namespace tg::compare

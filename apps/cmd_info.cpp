// tomograin info FILE: what a volume file holds.
#include <fmt/core.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "apps/command.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "core/stats.hpp"

namespace cmd_info {

struct Opts {
  std::string in;
  double voxel_um = 0;
  bool json = false;
};

int run_info(const Opts& o) {
  tg::ReadOptions ro;
  ro.voxel_um = o.voxel_um;
  ro.nonfinite = tg::NonFinite::allow;  // info reports them instead of refusing
  const tg::AnyVolume v = tg::read_volume(o.in, ro);
  const tg::Shape s = tg::shape_of(v);
  const tg::Geometry g = tg::geometry_of(v);
  const tg::DType dt = tg::dtype_of(v);
  const tg::VolumeStats st = tg::compute_stats(v);
  nlohmann::json j;
  j["file"] = o.in;
  j["format"] = [&] {
    switch (tg::format_of(o.in, false)) {
      case tg::FileFormat::tiff: return "tiff";
      case tg::FileFormat::tiff_folder: return "tiff-folder";
      case tg::FileFormat::raw: return "raw+json";
      case tg::FileFormat::hdf5: return "hdf5";
    }
    return "?";
  }();
  j["shape_zyx"] = {s.nz, s.ny, s.nx};
  j["voxels"] = s.voxels();
  j["dtype"] = tg::dtype_name(dt);
  j["bytes"] = s.voxels() * tg::dtype_bytes(dt);
  if (g.has_voxel_size()) j["voxel_size_um_zyx"] = {g.voxel_size_m[0] * 1e6, g.voxel_size_m[1] * 1e6, g.voxel_size_m[2] * 1e6};
  else j["voxel_size_um_zyx"] = nullptr;
  j["origin_m_zyx"] = g.origin_m;
  j["min"] = st.min;
  j["max"] = st.max;
  j["mean"] = st.mean;
  j["stddev"] = st.stddev;
  j["nonfinite_voxels"] = st.nonfinite;
  nlohmann::json pct;
  for (double p : {0.01, 1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0, 99.99}) pct[fmt::format("{:g}", p)] = st.percentile(p);
  j["percentiles"] = pct;
  if (dt == tg::DType::u16) {
    j["voxels_at_0"] = st.hist_lo == 0 ? st.count_at_min : 0;
    j["voxels_at_65535"] = st.max == 65535 ? st.count_at_max : 0;
  }
  if (st.distinct_nonzero >= 0) j["distinct_nonzero_labels"] = st.distinct_nonzero;
  const auto [path, ds] = tg::split_dataset_spec(o.in);
  if (tg::format_of(o.in, false) == tg::FileFormat::hdf5) j["hdf5_datasets"] = tg::H5Reader(path).datasets();

  if (o.json) {
    fmt::print("{}\n", j.dump(2));
    return 0;
  }
  fmt::print("file        {} ({})\n", o.in, j["format"].get<std::string>());
  fmt::print("shape       {} x {} x {} (z, y, x) = {} voxels, {} ({})\n", s.nz, s.ny, s.nx, s.voxels(),
             tg::dtype_name(dt), tg::human_bytes(static_cast<double>(s.voxels() * tg::dtype_bytes(dt))));
  if (g.has_voxel_size())
    fmt::print("voxel size  {:.6g} x {:.6g} x {:.6g} um (z, y, x); extent {:.4g} x {:.4g} x {:.4g} mm\n",
               g.voxel_size_m[0] * 1e6, g.voxel_size_m[1] * 1e6, g.voxel_size_m[2] * 1e6,
               s.nz * g.voxel_size_m[0] * 1e3, s.ny * g.voxel_size_m[1] * 1e3, s.nx * g.voxel_size_m[2] * 1e3);
  else
    fmt::print("voxel size  unknown (give --voxel-um to commands that need physical units)\n");
  fmt::print("origin      {:.6g}, {:.6g}, {:.6g} m (z, y, x)\n", g.origin_m[0], g.origin_m[1], g.origin_m[2]);
  fmt::print("values      min {:.6g}  max {:.6g}  mean {:.6g}  std {:.6g}\n", st.min, st.max, st.mean, st.stddev);
  if (st.nonfinite) fmt::print("NON-FINITE  {} NaN/Inf voxels (processing commands reject this file)\n", st.nonfinite);
  fmt::print("percentiles 0.01%: {:.6g}  1%: {:.6g}  50%: {:.6g}  99%: {:.6g}  99.99%: {:.6g}\n", st.percentile(0.01),
             st.percentile(1), st.percentile(50), st.percentile(99), st.percentile(99.99));
  if (dt == tg::DType::u16) {
    const int64_t at0 = j["voxels_at_0"], atmax = j["voxels_at_65535"];
    fmt::print("16-bit      {} voxels at 0 ({:.3g}%), {} at 65535 ({:.3g}%){}\n", at0, 100.0 * at0 / st.voxels, atmax,
               100.0 * atmax / st.voxels, atmax > st.voxels / 1000 ? "  <- saturated" : "");
  }
  if (st.distinct_nonzero >= 0) fmt::print("labels      {} distinct non-zero labels\n", st.distinct_nonzero);
  if (j.contains("hdf5_datasets")) {
    std::string list;
    for (const auto& d : j["hdf5_datasets"]) list += (list.empty() ? "" : ", ") + d.get<std::string>();
    fmt::print("datasets    {}\n", list);
  }
  return 0;
}

}  // namespace cmd_info

namespace cmd_info {
static tg::app::Registrar reg{{"info", 10,
      "Describe a volume: shape, element type, voxel size, value range, percentiles,\n"
      "16-bit saturation, NaN/Inf count, label count, HDF5 datasets.\n\n"
      "Examples:\n"
      "  tomograin info scan.tif\n"
      "  tomograin info slices/ --voxel-um 12.3\n"
      "  tomograin info specimen.h5:/labels --json",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("file", o->in, "Volume: .tif/.tiff, folder of slices, .json (raw sidecar), .h5[:/dataset]")
      ->required();
  tg::app::add_voxel_option(sub, o->voxel_um);
  sub->add_flag("--json", o->json, "Print the description as JSON");
  return [o] { return run_info(*o); };
}}};
}  // namespace cmd_info

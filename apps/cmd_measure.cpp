// tomograin measure LABELS -o particles.csv   the particle table
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>

#include "apps/command.hpp"
#include "apps/jobs.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "core/memory.hpp"
#include "core/progress.hpp"
#include "core/table.hpp"
#include "measure/measure_chunked.hpp"
#include "measure/particles.hpp"
#include "segmentation/threshold.hpp"

namespace cmd_measure {

namespace fs = std::filesystem;
using namespace tg;

}  // namespace cmd_measure

namespace tg::app {

namespace {
// The labels of `in`: an .h5 without a dataset name means its /labels (the
// file may also hold /volume).
std::string labels_spec(const std::string& in) {
  const auto [path, ds] = split_dataset_spec(in);
  if (format_of(in, false) == FileFormat::hdf5 && ds.empty() && H5Reader(path).has("/labels")) return path + ":/labels";
  return in;
}
}  // namespace

Volume<uint32_t> read_labels(const std::string& in, double voxel_um) {
  ReadOptions ro;
  ro.voxel_um = voxel_um;
  Volume<uint32_t> labels = read_label_volume(labels_spec(in), ro);
  if (!labels.geometry().has_voxel_size()) throw InputError(in + ": no voxel size in the file; give --voxel-um");
  return labels;
}

namespace {

// The table's text columns, for both paths.
void add_text_columns(Table& t, const measure::ParticleOptions& po, bool grey) {
  const std::string sizing = measure::sizing_name(po);
  t.add_text("sizing", std::vector<std::string>(static_cast<size_t>(t.rows()), sizing));
  // Which estimate volume_mm3 (and d_eq, d_med) holds; `voxels` is always the label's count.
  t.add_text("volume_from", std::vector<std::string>(static_cast<size_t>(t.rows()), grey ? "grey" : "voxels"));
}

void print_measured(const MeasureJob& o, const std::vector<measure::Particle>& particles,
                    const measure::ParticleOptions& po) {
  int64_t below = 0, border = 0;
  for (const auto& p : particles) {
    below += p.stats.below_limit;
    border += p.stats.touches_border;
  }
  fmt::print("{}: {} particles ({} below {:g} mm, {} touching the border); d_max/d_med/d_min = {}\n", o.in,
             particles.size(), below, o.limit_mm, border,
             po.sizing == measure::Sizing::obb ? "oriented-box edges (obb)"
                                               : "Feret calipers (" + measure::sizing_name(po) + ")");
}

// A uint16 grey scan read slab by slab (measure::GreySlabSource), each
// slab's slices alone: no copy of the whole scan; from HDF5 into one buffer,
// so no fresh pages after the first slab. `open` is false when the scan is
// not uint16 (the caller then reads and converts the whole scan).
struct GreyFile {
  std::string spec;
  VolumeInfo info;
  AnyVolume buf;
  bool open(const std::string& s) {
    spec = s;
    info = read_volume_info(s);
    return info.dtype == DType::u16;
  }
  Shape shape() const { return info.shape; }
  measure::GreySlabSource source() {
    return [this](int64_t z0, int64_t nz) -> const Volume<uint16_t>& {
      ReadOptions ro;
      ro.progress = false;
      ro.slices = {z0, nz};
      ro.reuse = &buf;
      buf = read_volume(spec, ro);
      const auto* g = std::get_if<Volume<uint16_t>>(&buf);
      if (!g) throw InputError(spec + ": slab-by-slab measuring reads uint16 grey scans only");
      return *g;
    };
  }
};

// The void and solid levels of a grey scan's histogram; `name` for errors.
PhaseLevels checked_levels(std::vector<int64_t> hist, const std::string& name) {
  PhaseLevels levels;
  try {
    levels = phase_levels(std::move(hist));
  } catch (const InputError& e) {
    throw InputError(name + ": " + e.what());
  }
  if (!(levels.solid > levels.void_level))
    throw InputError(fmt::format("{}: no separate void and solid grey levels (void {:.0f}, solid {:.0f})", name,
                                 levels.void_level, levels.solid));
  return levels;
}

// The same from the whole scan read slab by slab, `step` slices at a time.
PhaseLevels checked_levels(const measure::GreySlabSource& grey, int64_t nz, int64_t step, const std::string& name) {
  std::vector<int64_t> hist(65536, 0);
  for (int64_t z0 = 0; z0 < nz; z0 += step) {
    const auto h = histogram_u16(grey(z0, std::min(step, nz - z0)));
    for (size_t b = 0; b < hist.size(); ++b) hist[b] += h[b];
  }
  return checked_levels(std::move(hist), name);
}

// Labels (and grey scan) over --memory-limit: slab by slab from their files
// (any format; measure/measure_chunked.hpp), the same table. CSV output only
// (an .h5 output would copy the labels).
int run_measure_chunked(const MeasureJob& o, measure::ParticleOptions po, const Shape& shape, const Geometry& geom,
                        const measure::MeasureChunkPlan& plan, int64_t limit) {
  for (const auto& out : o.out)
    if (is_hdf5(out))
      throw UsageError("-o " + out + ": labels measured slab by slab (--memory-limit) give a .csv table only");
  if (po.surface)
    throw UsageError(o.in + ": surface areas need the whole label volume in memory; drop --surface (or "
                     "--memory-limit)");
  fmt::print("measuring {} ({}) slab by slab: about {} in one piece, over --memory-limit {}; first slab {} "
             "slices, then as the boundary lists leave room (planned {})\n",
             o.in, shape.str(), human_bytes(double(plan.estimate_bytes)), human_bytes(double(limit)), plan.core,
             human_bytes(double(plan.list_bytes)));
  const std::string lab_spec = labels_spec(o.in);
  measure::LabelSlabSource labels = [&](int64_t z0, int64_t nz) {
    ReadOptions ro;
    ro.progress = false;
    ro.slices = {z0, nz};
    Volume<uint32_t> l = read_label_volume(lab_spec, ro);
    l.set_geometry(geom);
    return l;
  };
  GreyFile gf;
  measure::GreySlabSource grey;
  PhaseLevels levels;
  if (!o.grey.empty()) {
    if (!gf.open(o.grey))
      throw UsageError(o.grey + ": with --memory-limit the grey scan is read slab by slab as uint16 only (this one is " +
                       dtype_name(gf.info.dtype) + "; tomograin convert --to uint16)");
    if (!(gf.shape() == shape))
      throw InputError(o.grey + ": grey scan " + gf.shape().str() + " is not the shape of the labels " + shape.str());
    grey = gf.source();
    // The phases' levels from the whole scan's histogram: one read first.
    levels = checked_levels(grey, shape.nz, std::max<int64_t>(1, plan.core), o.grey);
    po.grey_levels.void_grey = levels.void_level;
    po.grey_levels.solid_grey = levels.solid;
    po.grey_levels.local_solid = !o.grey_global_level;
  }
  Progress bar("measure slabs", double(shape.nz), "slices");
  measure::ChunkedMeasure res;
  try {
    res = measure::measure_particles_chunked(shape, geom, labels, grey, {0, limit}, po,
                                             [&](int64_t done, int64_t) { bar.update(double(done)); });
  } catch (const InputError& e) {
    throw InputError(o.in + ": " + e.what());
  }
  bar.finish();
  const std::vector<measure::Particle>& particles = res.particles;
  Table t = measure::particle_table(particles);
  add_text_columns(t, po, !o.grey.empty());
  for (const auto& out : o.out) write_csv(t, out);
  if (!o.grey.empty())
    fmt::print("volumes from the grey levels of {} (partial volume: void {:.0f}, solid {:.0f})\n", o.grey,
               levels.void_level, levels.solid);
  print_measured(o, particles, po);
  fmt::print("  {} slabs, {} boundary voxels ({:.3f} per voxel){}, peak memory {} ({:.2f} B/voxel)\n", res.slabs,
             res.boundary_voxels, double(res.boundary_voxels) / double(shape.voxels()),
             po.contacts ? fmt::format("; {} contacts, normals in {} slabs", res.contacts, res.normal_slabs) : "",
             human_bytes(double(peak_rss_bytes())), double(peak_rss_bytes()) / double(shape.voxels()));
  for (const auto& out : o.out) fmt::print("wrote {}\n", out);
  return 0;
}

}  // namespace

int run_measure(const MeasureJob& o) {
  measure::ParticleOptions po;
  parse_feret_option(o.feret, po.feret_exact, po.feret_directions);
  po.sizing = o.sizing == "obb" ? measure::Sizing::obb : measure::Sizing::feret;
  po.stats.detection_limit_m = o.limit_mm * 1e-3;
  po.face_offset = o.face_offset;
  po.oriented_box = o.box || po.sizing == measure::Sizing::obb;
  po.contacts = !o.no_contacts;
  po.surface = o.surface;
  po.convex = o.convex;
  if (!o.columns.empty()) {
    const std::vector<std::string> known{"coordination", "surface", "sphericity", "convex", "solidity", "obb"};
    auto has = [&](const char* c) { return std::find(o.columns.begin(), o.columns.end(), c) != o.columns.end(); };
    for (const auto& c : o.columns)
      if (std::find(known.begin(), known.end(), c) == known.end())
        throw UsageError("--columns: unknown column group '" + c +
                         "' (valid: coordination, surface, sphericity, convex, solidity, obb)");
    po.contacts = has("coordination");
    po.surface = has("surface") || has("sphericity");
    po.convex = has("convex") || has("solidity");
    po.oriented_box = has("obb") || po.sizing == measure::Sizing::obb;
  }
  po.threads = o.threads;
  po.obb.random_seed = o.seed;
  for (const auto& out : o.out) {
    const auto e = std::filesystem::path(out).extension().string();
    if (e != ".csv" && !is_hdf5(out)) throw UsageError("-o " + out + ": expected a .csv or .h5 file");
  }

  const std::string path = split_dataset_spec(o.in).first;
  if (!o.memory_limit.empty() && !o.labels) {
    const int64_t limit = parse_byte_size(o.memory_limit);
    if (limit <= 0)
      throw UsageError("--memory-limit " + o.memory_limit + ": not a size (e.g. 16GiB, 512MiB, 2G, 1000000000)");
    // The labels' shape without reading their voxels (any format).
    ReadOptions ro;
    ro.voxel_um = o.voxel_um;
    const VolumeInfo info = read_volume_info(labels_spec(o.in), ro);
    if (!info.geometry.has_voxel_size()) throw InputError(o.in + ": no voxel size in the file; give --voxel-um");
    // A uint16 grey scan is read slab by slab below (in one buffer from HDF5).
    measure::GreyHeld held = measure::GreyHeld::none;
    if (!o.grey.empty()) {
      GreyFile probe;
      held = probe.open(o.grey) ? measure::GreyHeld::slabs : measure::GreyHeld::whole;
    }
    const auto plan = measure::plan_measure_chunks(info.shape, held, limit);
    if (!plan.in_memory) return run_measure_chunked(o, po, info.shape, info.geometry, plan, limit);
  }
  Volume<uint32_t> read;
  if (!o.labels) read = read_labels(o.in, o.voxel_um);
  const Volume<uint32_t>& labels = o.labels ? *o.labels : read;
  if (!labels.geometry().has_voxel_size()) throw InputError(o.in + ": no voxel size in the file; give --voxel-um");

  // With the grey scan, volumes from its grey levels (measure/grey_volume.hpp).
  // A uint16 HDF5 scan is read slab by slab (twice: the histogram, then the
  // volumes), into one buffer of ~256 MiB: reading a 1220^3 scan whole into
  // fresh memory took ~6 s of kernel page clearing alone, and 2 B/voxel.
  // So is a uint16 scan of another format under --memory-limit (the plan
  // above counted it in slabs; each slab's slices read alone, twice).
  // Otherwise other formats and types are read whole (and converted to 16 bits).
  Volume<uint16_t> grey;
  VolumeView<const uint16_t> grey_view;
  GreyFile gf;
  measure::GreySlabSource grey_slabs;
  PhaseLevels levels;
  if (!o.grey.empty()) {
    if ((is_hdf5(o.grey) || !o.memory_limit.empty()) && gf.open(o.grey)) {
      if (!(gf.shape() == labels.shape()))
        throw InputError(o.grey + ": grey scan " + gf.shape().str() + " is not the shape of the labels " +
                         labels.shape().str());
      grey_slabs = gf.source();
      levels = checked_levels(grey_slabs, labels.shape().nz, measure::grey_window_slices(labels.shape()), o.grey);
      po.grey_slabs = &grey_slabs;
    } else {
      int top = 65535;
      grey = read_grey(o.grey, o.voxel_um, top);
      grey_view = grey.view();
      if (!(grey.shape() == labels.shape()))
        throw InputError(o.grey + ": grey scan " + grey.shape().str() + " is not the shape of the labels " +
                         labels.shape().str());
      levels = checked_levels(histogram_u16(grey), o.grey);
      po.grey = &grey_view;
    }
    po.grey_levels.void_grey = levels.void_level;
    po.grey_levels.solid_grey = levels.solid;
    po.grey_levels.local_solid = !o.grey_global_level;
  }
  const auto particles = measure::measure_particles(labels.view(), po);
  Table t = measure::particle_table(particles);
  add_text_columns(t, po, !o.grey.empty());
  const std::string sizing = measure::sizing_name(po);

  for (const auto& out : o.out) {
    if (!is_hdf5(out)) {
      write_csv(t, out);
      continue;
    }
    // The table beside the labels; writing into the input file keeps its
    // /volume but refuses to drop anything else.
    std::vector<std::pair<std::string, AnyVolume>> keep;
    if (std::filesystem::exists(out) && std::filesystem::exists(path) && std::filesystem::equivalent(out, path)) {
      H5Reader r(path);
      for (const auto& d : r.datasets()) {
        if (d == "/labels" || d.rfind("/particles/", 0) == 0) continue;
        if (d != "/volume")
          throw UsageError(out + " holds " + d + ", which rewriting it would drop: write the table to another .h5");
        keep.emplace_back(d, r.read_volume(d));
      }
    }
    H5Writer w(out);
    for (const auto& [name, v] : keep) w.write_volume(name, v);
    w.write_volume("/labels", labels);
    w.write_table("/particles", t);
    w.write_attribute("particles_sizing", sizing);
    w.commit();
  }
  if (!o.grey.empty())
    fmt::print("volumes from the grey levels of {} (partial volume: void {:.0f}, solid {:.0f})\n", o.grey,
               levels.void_level, levels.solid);
  print_measured(o, particles, po);
  for (const auto& out : o.out) fmt::print("wrote {}\n", out);
  return 0;
}

}  // namespace tg::app

namespace cmd_measure {

tg::app::Registrar reg_measure{{"measure", 40,
      "Per-particle volume, centroid, size and shape from a label volume.\n\n"
      "Reads u32 labels (0 = void; an .h5 file's /labels by default) and writes one row per label:\n"
      "label, voxels, volume_mm3, cx_mm, cy_mm, cz_mm, d_eq_mm (equal-volume sphere), d_max_mm,\n"
      "d_min_mm, d_med_mm, fr = d_min/d_med, ar = d_max/d_min, obb_max/med/min_mm (CGAL oriented box),\n"
      "touches_border, below_limit, then the raw Feret calipers, bounding box and principal moments,\n"
      "the equivalent ellipsoid (ell_d1/2/3_mm, ell_axis1_z/y/x), convex_volume_mm3 and solidity with --convex,\n"
      "coordination (contacts with other labels, as `tomograin contacts` finds them), surface_mm2 and\n"
      "sphericity with --surface, and a `sizing` column naming the definition behind d_max/d_med/d_min.\n"
      "With --grey SCAN (the scan the labels came from), volume_mm3 is the partial-volume estimate from its\n"
      "grey levels (the void lines between touching grains and the threshold's offset cost the voxel count\n"
      "~2 % at 20 voxels radius; measure/grey_volume.hpp), d_eq_mm follows it, label_volume_mm3 keeps the\n"
      "label's volume (d_med_mm and fr stay on it, like the calipers) and `volume_from` says grey or voxels.\n"
      "obb_* are 0 unless --box. fr is clamped to 1 where d_min > d_med (non-convex particles), and\n"
      "fr_clamped says where (docs/measure.md).\n"
      "Sizing 'feret' (default): calipers of the convex hull at --feret N quasi-uniform orientations\n"
      "(60, as in the reference study) or 'exact' (hull diameter and exact minimum widths: slower,\n"
      "the reference for N's bias); d_min is the smallest caliper perpendicular to d_max (its\n"
      "direction fitted over diameters within half a voxel of it, so flat fragments get their\n"
      "thickness) and d_med = 6V/(pi d_max d_min). Sizing 'obb': the oriented box's edges.\n"
      "Hull points sit a --face-offset fraction of half a voxel beyond each boundary voxel's\n"
      "centre, which keeps calipers of digitised spheres within ~0.3 % (measure/feret.hpp).\n"
      "Lengths in mm from the file's voxel size (or --voxel-um).\n\n"
      "Examples:\n"
      "  tomograin measure labels.h5 -o particles.csv\n"
      "  tomograin measure labels.h5 --grey scan.h5:/scan -o particles.csv\n"
      "  tomograin measure labels.h5 -o particles.csv -o particles.h5 --feret exact\n"
      "  tomograin measure labels.tif --voxel-um 11.6 --sizing obb -o particles.csv\n"
      "  tomograin measure big_labels.h5 --grey big_scan.h5:/scan --memory-limit 16GiB -o particles.csv",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<tg::app::MeasureJob>();
  sub->add_option("labels", o->in, "Label volume (u32): .h5[:/dataset], .tif, folder of slices, raw .json")->required();
  sub->add_option("-o,--output", o->out,
                  "Output table(s): .csv, or .h5 (/labels + /particles table; naming the input .h5 adds the "
                  "table to it). Repeatable: -o a.csv -o a.h5")
      ->required()
      ->allow_extra_args(false);  // one file per -o, so a positional after it stays the input
  sub->add_option("--feret", o->feret, "Feret orientations N (>= 3) or 'exact'")->default_str("60");
  sub->add_option("--sizing", o->sizing, "Definition behind d_max/d_med/d_min: feret or obb")
      ->check(CLI::IsMember({"feret", "obb"}))
      ->default_str("feret");
  sub->add_option("--detection-limit-mm", o->limit_mm, "Flag particles with d_eq below this (mm)")
      ->check(CLI::PositiveNumber)
      ->default_str("0.2");
  sub->add_option("--face-offset", o->face_offset,
                  "Hull points: boundary voxel centre + this x half a voxel towards each exposed face, in (0, 1] "
                  "(measure/feret.hpp explains the 0.3 default)")
      ->default_str("0.3");
  sub->add_flag("--box", o->box,
                "Also compute CGAL's oriented box (obb_* columns; implied by --sizing obb). Off by default: "
                "on real scans it took ~85 % of the time");
  sub->add_flag("--no-box", o->no_box, "Accepted for old scripts: the box is off unless --box");
  sub->add_flag("--no-contacts", o->no_contacts, "Skip the coordination column (contact search)");
  sub->add_option("--columns", o->columns,
                  "Optional column groups to compute, comma-separated, instead of the flags: coordination, "
                  "surface, sphericity, convex, solidity, obb (e.g. --columns coordination,sphericity; "
                  "the size/shape columns are always there)")
      ->delimiter(',');
  sub->add_flag("--convex", o->convex, "Also convex_volume_mm3 and solidity (builds the CGAL hull)");
  sub->add_flag("--surface", o->surface,
                "Also surface_mm2 (normal-weighted voxel faces, within 0.2 % on spheres of radius >= 20 voxels) "
                "and Wadell sphericity; costs several times the Feret step");
  sub->add_option("--seed", o->seed, "Random seed of CGAL's oriented-box optimiser")->default_str("42");
  sub->add_option("--grey", o->grey,
                  "The grey scan the labels were segmented from: volume_mm3 and d_eq_mm become partial-volume "
                  "estimates from its grey levels, void lines and threshold bias included "
                  "(measure/grey_volume.hpp); d_med_mm and fr stay on the labels; volume_from says which. Each "
                  "particle's surface band is read against its own solid level (the grey of its core), so that "
                  "beam hardening (a darker centre) or grains of different density do not bias it");
  sub->add_flag("--grey-global-level", o->grey_global_level,
                "With --grey: read every particle's band against the scan's solid level instead of its own "
                "(the estimate before the local level; blind sweep, cupping 0.3: median |dV/V| 2.9 % against 0.3 %)");
  sub->add_option("--memory-limit", o->memory_limit,
                  "Memory to stay under, e.g. 16GiB, 512MiB, 2G or a byte count. Labels (any format) whose measuring "
                  "needs more (~5 B/voxel, 7 with a --grey scan read whole; a uint16 one is read in slabs) are measured slab by slab, with the same table; .csv "
                  "output only");
  tg::app::add_threads_option(sub, o->threads);
  tg::app::add_voxel_option(sub, o->voxel_um);
  return [o] { return tg::app::run_measure(*o); };
}}};

}  // namespace cmd_measure

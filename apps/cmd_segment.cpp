// tomograin segment SCAN -o labels.h5: grey scan -> one label per grain.
#include <fmt/core.h>

#include <filesystem>
#include <fstream>

#include "apps/command.hpp"
#include "apps/jobs.hpp"
#include "core/atomic_file.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "segmentation/normalise.hpp"
#include "segmentation/segment.hpp"
#include "segmentation/segment_chunked.hpp"
#include "core/memory.hpp"

namespace cmd_segment {

// Any input type as u16: float32 is normalised (auto range, printed), u8
// widened. `top` is the input's saturation level in the u16 grey (255 for u8).
tg::Volume<uint16_t> to_grey(tg::AnyVolume&& v, const std::string& name, int& top) {
  top = 65535;
  if (auto* g = std::get_if<tg::Volume<uint16_t>>(&v)) return std::move(*g);
  if (auto* f = std::get_if<tg::Volume<float>>(&v)) {
    const auto r = tg::auto_range(*f);
    fmt::print("float32 input: normalised to 16 bits, [{:.6g}, {:.6g}] -> [0, 65535] ({})\n", r.lo, r.hi, r.how);
    return tg::normalise_to_u16(*f, r);
  }
  if (auto* b = std::get_if<tg::Volume<uint8_t>>(&v)) {
    top = 255;
    tg::Volume<uint16_t> g(b->shape(), b->geometry());
    for (int64_t i = 0; i < b->size(); ++i) g[i] = (*b)[i];
    return g;
  }
  throw tg::InputError(name + ": holds uint32 (labels?); expected a grey scan (uint16, float32 or uint8)");
}

}  // namespace cmd_segment

namespace tg::app {

// The grey 3-D datasets of an HDF5 file (not uint32): for the message when
// the default dataset of a file holding a scan and its labels is the labels.
std::string grey_datasets(const std::string& in) {
  const auto [path, ds] = tg::split_dataset_spec(in);
  if (!ds.empty() || tg::format_of(path, false) != tg::FileFormat::hdf5) return "";
  std::string listed;
  try {
    const tg::H5Reader r(path);
    for (const auto& d : r.datasets())
      if (r.rank(d) == 3 && tg::read_volume_info(path + ":" + d).dtype != tg::DType::u32)
        listed += (listed.empty() ? "" : ", ") + path + ":" + d;
  } catch (const std::exception&) {
    return "";
  }
  return listed;
}

Volume<uint16_t> read_grey(const std::string& in, double voxel_um, int& top) {
  tg::ReadOptions ro;
  ro.voxel_um = voxel_um;
  // Checked before the read: the labels of a large scan take a while.
  if (tg::read_volume_info(in, ro).dtype == tg::DType::u32) {
    const std::string grey = grey_datasets(in);
    if (!grey.empty())
      throw tg::InputError(in + ": its default dataset holds uint32 labels; the grey scan is another dataset, name it: " +
                           grey);
  }
  return cmd_segment::to_grey(tg::read_volume(in, ro), in, top);
}

namespace {

// The options from the command line, for a scan of geometry geom whose top
// grey level is `top`.
tg::SegmentOptions segment_options(const SegmentJob& o, const tg::Geometry& geom, int top) {
  tg::SegmentOptions s = o.seg;
  s.saturation_level = top;
  s.threshold = tg::parse_threshold_method(o.threshold);
  if (s.local_window_vox > 0 && s.threshold != tg::ThresholdMethod::local) {
    if (o.threshold != "moments")
      throw tg::UsageError("--local-window-vox is the window of --threshold local, not of --threshold " + o.threshold);
    s.threshold = tg::ThresholdMethod::local;
  }
  s.fov.detect = !o.no_fov;
  if (!o.fov_centre.empty()) {
    if (o.fov_centre.size() != 2) throw tg::UsageError("--fov-centre-vox takes Y,X (two numbers)");
    s.fov.centre_y = o.fov_centre[0];
    s.fov.centre_x = o.fov_centre[1];
  }
  s.manual_threshold = o.manual;
  if (s.threshold == tg::ThresholdMethod::manual && o.manual < 0)
    throw tg::UsageError("--threshold manual needs --manual-value GREY");
  s.fill_pores = !o.no_pores;
  s.watershed_lines = !o.no_lines;
  s.merge = !o.no_merge;
  s.split = !o.no_split;
  s.face_caps = !o.no_face_caps;
  s.thin_pieces = !o.no_thin_pieces;
  s.face_slivers = !o.no_face_slivers;
  s.grain_levels = !o.no_grain_levels;
  s.noise_specks = !o.keep_noise_specks;
  s.grey_evidence = !o.no_grey_evidence;
  if (o.grain_radius_vox > 0) {
    s.grain_radius_vox = o.grain_radius_vox;
  } else {
    if (!geom.has_voxel_size())
      throw tg::UsageError(o.in + ": no voxel size in the file; give --voxel-um or --grain-radius-vox");
    s.grain_radius_vox = tg::grain_radius_in_voxels(o.grain_diameter_um * 1e-6 / 2.0, geom);
  }
  return s;
}

void print_plan(const SegmentJob& o, const tg::SegmentOptions& s) {
  const auto r = s.resolved();
  fmt::print("  pores: {}\n", s.fill_pores ? tg::PoreFilterOptions{r.pore_max_volume_vox, r.pore_min_sphericity}.describe()
                                            : std::string("not filled"));
  fmt::print("  markers: h-maxima of the distance map, h = {:.3g} voxels; watershed {}; merge ratio {}\n", r.h,
             s.watershed_lines ? "with lines" : "without lines", s.merge ? fmt::format("{}", s.merge_ratio) : "off");
  fmt::print("  split repair: {}\n",
             s.split ? fmt::format("labels whose grey, smoothed over {} voxels, holds two cores {:.3g} noise sigmas "
                                   "above the sheet between them are cut apart ({:.3g} where the noise is correlated)",
                                   s.split_smoothing_vox > 0 ? fmt::format("{:.3g}", s.split_smoothing_vox)
                                                             : std::string("0.7 or 1 (from the noise)"),
                                   s.split_depth_sigmas, s.split_depth_sigmas_correlated)
                     : std::string("off"));
  fmt::print("  thin pieces: {}\n",
             s.split && s.thin_pieces
                 ? fmt::format("a piece of a label thinner than 2 x {:.3g} voxels (outside its opening by a ball of that "
                               "radius) that touches the rest by under a fifth of its voxels gets a label of its own "
                               "(a chip pressed on a grain); {}",
                               r.thin_piece_radius_vox,
                               r.merges_thin_walls()
                                   ? "labels thin throughout meeting across a bright interface merged (a shell's wall)"
                                   : "walls not merged (grains under 2 (r + 1) voxels are thin throughout themselves)")
                 : std::string("off"));
  fmt::print("  face caps: {}\n", s.split && s.face_caps
                                     ? "a label whose footprint on a scan face holds two distance maxima parted by a "
                                       "dim contact, or goes on behind its footprint past a dim layer into a grain, "
                                       "gives up the cap of the grain cut by the face"
                                     : "off");
  fmt::print("  grain levels: {}\n",
             s.grain_levels && s.split && s.threshold != tg::ThresholdMethod::local
                 ? fmt::format("where the grains differ in brightness (the smoothed solid peak >= {:g} x the grey's "
                               "spread inside a grain, or a darker population's own peak >= {:g} x its floors), each "
                               "grain's grey is raised to the brightest grains' level before the threshold",
                               tg::GrainLevelsOptions{}.min_spread_ratio, tg::kDimPopulationProminence)
                 : std::string("off"));
  fmt::print("  face slivers: {}\n", s.face_slivers && s.threshold != tg::ThresholdMethod::local
                                        ? "labels lying within 2 voxels of a scan face take the voxels beside them "
                                          "above half their own contrast over the void, where that is below the "
                                          "threshold (dim, partial-volume slivers); the size floor applies after"
                                        : "off");
  fmt::print("  noise specks: {}\n", s.noise_specks ? fmt::format("labels whose mean grey is void noise over the "
                                                                 "threshold (z < {:.3g}) and that have no core are "
                                                                 "cleared", s.speck_z)
                                                   : std::string("kept"));
  (void)o;
}

// A scan that does not fit under --memory-limit: slab by slab from its
// file (any format: each slab's slices alone) into the labels' HDF5 file
// (segment_chunked.hpp).
int run_segment_chunked(const SegmentJob& o, const tg::Shape& shape, const tg::Geometry& geom,
                        const tg::ChunkedOptions& co) {
  const auto [path, ds] = tg::split_dataset_spec(o.out);
  if (tg::format_of(o.out, true) != tg::FileFormat::hdf5)
    throw tg::UsageError(o.out + ": a scan segmented slab by slab (--memory-limit) is written to HDF5 only");
  tg::SegmentOptions s = segment_options(o, geom, 65535);
  const tg::ChunkPlan plan = tg::plan_chunks(shape, s.resolved().grain_radius_vox, co);
  fmt::print("segmenting {} ({}) slab by slab: {} over --memory-limit {}; {} slabs of {} core + 2 x {} margin "
             "slices (~{} each), expected grain radius {:.3g} voxels\n",
             o.in, shape.str(), tg::human_bytes(double(plan.estimate_bytes)),
             tg::human_bytes(double(co.memory_limit_bytes)), plan.slabs, plan.core, plan.margin,
             tg::human_bytes(double(plan.slab_bytes)), s.resolved().grain_radius_vox);
  print_plan(o, s);
  auto read = [&](int64_t z0, int64_t nz) {
    tg::ReadOptions ro;
    ro.voxel_um = o.voxel_um;  // as the whole scan's reader applies it
    ro.progress = false;
    ro.slices = {z0, nz};
    tg::AnyVolume v = tg::read_volume(o.in, ro);
    auto* g = std::get_if<tg::Volume<uint16_t>>(&v);
    if (!g) throw tg::InputError(o.in + ": slab-by-slab segmentation (--memory-limit) reads uint16 scans only");
    return std::move(*g);
  };
  const std::string out_ds = ds.empty() ? "/labels" : ds;
  tg::H5Writer w(path);
  w.create_volume(out_ds, tg::DType::u32, shape, geom, o.compression);
  auto write = [&](int64_t z0, const tg::Volume<uint32_t>& l, int64_t vz0, int64_t nz) {
    w.write_slab(out_ds, z0, l, vz0, nz);
  };
  tg::ChunkedResult res;
  try {
    res = tg::segment_chunked(shape, geom, read, write, s, plan);
  } catch (const tg::InputError& e) {
    throw tg::InputError(o.in + ": " + e.what());
  }
  const std::string summary_text = tg::summary_json(res, s);
  w.write_attribute("segment_summary", summary_text);
  w.commit();
  const auto& r = res.result;
  fmt::print("  threshold {} = {} (voxels above are solid), solid fraction {:.4f}{}\n",
             tg::threshold_method_name(r.threshold.method), r.threshold.value, r.solid_fraction,
             r.fov.active ? " (of the field of view)" : "");
  if (r.threshold.method == tg::ThresholdMethod::automatic) fmt::print("  threshold auto: {}\n", r.threshold.automatic.why);
  for (const auto& n : r.notes) fmt::print("  note: {}\n", n);
  fmt::print("  labels {} ({} dropped below {} voxels)\n", r.count, r.dropped, s.resolved().min_size_vox);
  fmt::print("  pass 1 {:.2f} s ({} read{}), pass 2 {:.2f} s ({} slabs), peak memory {} ({:.2f} B/voxel)\n",
             res.pass1_seconds, res.pass1_reads, res.pass1_reads > 1 ? "s" : "", res.pass2_seconds, res.plan.slabs,
             tg::human_bytes(double(r.peak_rss_bytes)), double(r.peak_rss_bytes) / double(shape.voxels()));
  std::string summary = o.summary;
  if (summary.empty()) summary = std::filesystem::path(path).replace_extension(".segment.json").string();
  tg::write_file_atomic(summary, summary_text + "\n");
  fmt::print("wrote {} ({}, uint32) and {}\n", path, out_ds, summary);
  return 0;
}

}  // namespace

int run_segment(SegmentJob& o) {
  tg::ChunkedOptions co;
  co.margin_vox = o.slab_margin_vox;
  if (!o.memory_limit.empty()) {
    co.memory_limit_bytes = tg::parse_byte_size(o.memory_limit);
    if (co.memory_limit_bytes <= 0)
      throw tg::UsageError("--memory-limit " + o.memory_limit + ": not a size (e.g. 16GiB, 512MiB, 2G, 1000000000)");
    // The scan's shape without reading its voxels (any format).
    tg::ReadOptions ro;
    ro.voxel_um = o.voxel_um;
    const tg::VolumeInfo info = tg::read_volume_info(o.in, ro);
    const tg::SegmentOptions so = segment_options(o, info.geometry, 65535);
    const double radius = so.resolved().grain_radius_vox;
    co.bytes_per_voxel = tg::segment_bytes_per_voxel(so);
    if (!tg::plan_chunks(info.shape, radius, co).in_memory) {
      if (info.dtype != tg::DType::u16)
        throw tg::UsageError(o.in + ": slab-by-slab segmentation (--memory-limit) reads uint16 scans only (this one "
                             "is " + tg::dtype_name(info.dtype) + "; tomograin convert --to uint16)");
      return run_segment_chunked(o, info.shape, info.geometry, co);
    }
  }
  int top = 65535;
  tg::Volume<uint16_t> grey = read_grey(o.in, o.voxel_um, top);
  const tg::Geometry geom = grey.geometry();
  if (co.memory_limit_bytes > 0) {
    const tg::ChunkPlan plan =
        tg::plan_chunks(grey.shape(), 1.0, {co.memory_limit_bytes, 0, tg::segment_bytes_per_voxel(segment_options(o, geom, top))});
    if (!plan.in_memory)
      throw tg::UsageError(o.in + ": segmenting it needs about " + tg::human_bytes(double(plan.estimate_bytes)) +
                           ", over --memory-limit");
  }

  tg::SegmentOptions s = segment_options(o, geom, top);
  const auto r = s.resolved();
  fmt::print("segmenting {} ({}), expected grain radius {:.3g} voxels\n", o.in, grey.shape().str(), r.grain_radius_vox);
  print_plan(o, s);

  tg::SegmentResult res;
  try {
    res = tg::segment(std::move(grey), s);
  } catch (const tg::InputError& e) {
    throw tg::InputError(o.in + ": " + e.what());  // the library does not know the file
  }
  if (res.threshold.method == tg::ThresholdMethod::local)
    fmt::print("  threshold local: blocks of {} voxels, {} bimodal, {} from neighbours, {:.0f}..{:.0f} (global moments "
               "{}), solid fraction {:.4f}\n",
               res.local.window, res.local.trusted, res.local.filled, res.local.min, res.local.max,
               res.threshold.value, res.solid_fraction);
  else
    fmt::print("  threshold {} = {} (voxels above are solid), solid fraction {:.4f}{}\n",
               tg::threshold_method_name(res.threshold.method), res.threshold.value, res.solid_fraction,
               res.fov.active ? " (of the field of view)" : "");
  if (res.threshold.method == tg::ThresholdMethod::automatic)
    fmt::print("  threshold auto: {}\n", res.threshold.automatic.why);
  for (const auto& n : res.notes) fmt::print("  note: {}\n", n);
  if (res.graded)
    fmt::print("  grey evidence: solid above {} is bright; {:.1f} % of the solid dim; {} dim pockets filled\n",
               res.bright_value, 100.0 * res.dim_fraction, res.dim_pockets.filled);
  fmt::print("  pores filled {} of {} enclosed; markers {}; merges {}; labels {} ({} dropped below {} voxels)\n",
             res.pores.filled, res.pores.enclosed, res.markers, res.merge.merges, res.count, res.dropped,
             r.min_size_vox);
  if (res.split_used)
    fmt::print("  split repair: {} of {} labels split ({} pieces added); depth {:.0f} grey levels (noise sigma {:.0f} "
               "smoothed over {:.2g} voxels)\n",
               res.split.split, res.split.tested, res.split.pieces_added, res.split_depth, res.smoothed_noise_sigma,
               res.split_smoothing_vox);
  if (res.thin_pieces_used && res.thin_pieces.split)
    fmt::print("  thin pieces: {} of {} labels gave up a thin piece ({} pieces added; opening radius {:.3g} voxels)\n",
               res.thin_pieces.split, res.thin_pieces.tested, res.thin_pieces.pieces_added, res.thin_piece_radius_vox);
  if (res.thin_walls_used && res.thin_walls.merges)
    fmt::print("  thin walls: {} merges among {} labels thin throughout\n", res.thin_walls.merges,
               res.thin_walls.thin_labels);
  if (res.face_slivers_used && res.face_slivers.labels_grown)
    fmt::print("  face slivers: {} thin labels on the scan's faces took {} partial-volume voxels\n",
               res.face_slivers.labels_grown, res.face_slivers.voxels_added);
  if (res.face_caps_used && res.face_caps.candidates)
    fmt::print("  face caps: {} of {} candidate labels on the scan's faces split ({} pieces added)\n",
               res.face_caps.split, res.face_caps.candidates, res.face_caps.pieces_added);
  double total = 0;
  for (const auto& [name, sec] : res.stage_seconds) total += sec;
  fmt::print("  {:.2f} s, peak memory {} ({:.1f} B/voxel)\n", total, tg::human_bytes(double(res.peak_rss_bytes)),
             res.labels.size() ? double(res.peak_rss_bytes) / double(res.labels.size()) : 0.0);

  const auto [path, ds] = tg::split_dataset_spec(o.out);
  if (tg::format_of(o.out, true) == tg::FileFormat::hdf5) {
    tg::H5Writer w(path);
    w.write_volume(ds.empty() ? "/labels" : ds, res.labels, o.compression);
    w.write_attribute("segment_summary", tg::summary_json(res, s));
    w.commit();
  } else {
    tg::write_volume(res.labels, o.out);
  }
  std::string summary = o.summary;
  if (summary.empty()) summary = std::filesystem::path(path).replace_extension(".segment.json").string();
  tg::write_file_atomic(summary, tg::summary_json(res, s) + "\n");
  fmt::print("wrote {} (/labels, uint32) and {}\n", path, summary);
  if (o.keep_labels) *o.keep_labels = std::move(res.labels);
  return 0;
}

}  // namespace tg::app

namespace cmd_segment {
static tg::app::Registrar reg{{"segment", 30,
    "Segment a grey scan into one label per grain or fragment (reference study section 2.2):\n"
    "moment-preserving threshold (Tsai 1985, as Fiji 'Moments'; voxels above it are solid),\n"
    "filling of small near-spherical enclosed pores, exact Euclidean distance map, h-maxima\n"
    "markers (one per grain and per split fragment), marker-controlled watershed with 1-voxel\n"
    "void lines between touching grains, merging of over-segmented pieces, size filter.\n"
    "--threshold auto: halfway between the void and solid peaks (the level a blurred surface\n"
    "crosses at its true place) when that is at least k noise sigmas (the noisier phase's) above\n"
    "the void peak, k such that noise lifts about one of the scan's N void voxels that far\n"
    "(k = 5.0 for N = 3e6); else Tsai's level, or k sigmas above the void if that is lower. The\n"
    "summary's threshold.auto says which and why. Smaller label volume error than Tsai (1.4 %\n"
    "against 2.2 % median |dV/V| on the blind sweep's middle setting), same F1 within noise.\n"
    "Grey evidence: solid darker than halfway between the threshold and the mean solid grey\n"
    "(and at least 3 noise sigmas below the solid's peak) is 'dim': partial volume at grain\n"
    "surfaces and in the blurred gap between two fragments a voxel apart. The distance map\n"
    "stops at dim voxels, so fragments keep one marker each even where noise bridges their gap,\n"
    "and a merge needs a mostly bright interface: past halfway from t to the two pieces' own\n"
    "mean grey (grains of different brightness each weighed against their own). The grading is\n"
    "off on very noisy scans (CNR below ~6); the merge's own test stays.\n"
    "Repairs after the watershed (the plan printed at the start says which run, the summary what\n"
    "each changed): noise specks cleared; split repair: a label whose smoothed grey holds two bright\n"
    "cores parted by a darker sheet (fragments a voxel apart) is cut along it (--no-split; the\n"
    "sheet at least 6 sigmas deeper (4 where the noise is correlated, as a reconstruction filter\n"
    "leaves it: split.noise_correlation): of the smoothed grey's variation inside grains or of\n"
    "the smoothed solid peak, whichever is smaller (grains of different brightness widen the\n"
    "peak): the summary's split.noise_from); thin pieces: a chip pressed on a grain (thinner than the\n"
    "ball of radius max(3, 0.15 R) whose opening keeps the grain, touching it by a small\n"
    "contact; at a face of the scan only from (3 r)^3 voxels up) gets its own label, and\n"
    "labels thin throughout that meet across an interface as bright as solid are put back\n"
    "together (the wall of a shell, which the watershed cuts where grains touch it; only where\n"
    "R >= 2 (r + 1): smaller grains are thin throughout themselves) (--no-thin-pieces);\n"
    "face caps: a grain cut by a face\n"
    "of the scan that shows only a thin cap, given by the watershed to the grain it touches,\n"
    "gets its own label when its section on\n"
    "the face is a second disc and the contact between them is dim, or when the label goes on\n"
    "behind the cap, past a dim layer, into a grain whose pole it is pressed on (--no-face-caps);\n"
    "face slivers: a grain the face cuts a voxel or two from its edge is all partial volume;\n"
    "where it is dim (a volume imaged alone), its label (within 2 voxels of the face) takes the\n"
    "voxels beside it above half its own contrast over the void, before the size floor\n"
    "(--no-face-slivers).\n"
    "Grain levels: where the grains differ in brightness (porous grains: the smoothed solid peak\n"
    "at least twice as wide as the grey varies inside a grain; another mineral: a peak of its own\n"
    "between the void and the solid), each voxel's grey is raised by (solid - void) / (M - void),\n"
    "M the brightest smoothed grey within 3 voxels, so one threshold cuts every grain at half its\n"
    "own contrast; dim grains are read from the grey smoothed over a voxel (their raw noise is too\n"
    "close to the void's). A container's wall of intermediate grey is raised too: mask it or give\n"
    "--no-grain-levels.\n"
    "Defaults derive from the expected grain radius R in voxels: pores up to 2 % of a grain's\n"
    "volume are filled (a pore the scan's face cuts too: the face closes it); marker depth\n"
    "h = max(0.5, 0.035 R) voxels (bumps grow with the grain;\n"
    "fragments smaller than the grains keep their markers).\n"
    "Distances are in voxels of the finest axis.\n"
    "Writes labels (uint32, 0 = void) to /labels of the HDF5 output and a JSON summary\n"
    "(threshold, pore criteria and pores filled, markers, merges, labels, seconds per stage,\n"
    "peak memory) beside it as OUTPUT.segment.json. float32 input is normalised to 16 bits\n"
    "first (auto range).\n\n"
    "Real scans, before the threshold (the summary's field_of_view and saturation objects):\n"
    "  field of view: when every slice's corners hold one constant (a reconstruction's outside),\n"
    "    the circle bounding the non-constant region is fitted; voxels outside it are neither\n"
    "    in the histogram nor labelled. Give it with --fov-radius-vox (centre: the slice centre\n"
    "    or --fov-centre-vox), or turn the detection off with --no-fov.\n"
    "  pre-masked zeros: voxels exactly 0 are a mask, not data, when they are >= 1 % of the voxels\n"
    "    and the next 1/256 of the grey range holds < 1/100 as many (a real void is noisy):\n"
    "    left out of the histogram, never solid.\n"
    "  saturation: a top level (65535; 255 for 8-bit input) or clipped 0 holding > 0.1 % of the\n"
    "    voxels is left out of the histogram (kept solid / void) with a note; > 50 % saturated\n"
    "    is an error (exit 2).\n"
    "  uneven brightness (cupping, drift along z): --threshold local, Tsai per block of\n"
    "    --local-window-vox voxels (default 4 R), interpolated between block centres.\n"
    "  ring artefacts (a dark ring cuts the grains it crosses): remove them first with\n"
    "    tomograin convert SCAN -o CLEAN.h5 --rings.\n\n"
    "Scans larger than memory: with --memory-limit, a uint16 scan (any format: each slab's slices\n"
    "are read alone) whose segmentation needs more than the limit (~8 B/voxel + 128 MiB) is\n"
    "segmented slab by slab along z into an HDF5 labels file: one pass for\n"
    "the field of view, histogram and threshold, then slabs of core slices (a multiple of 16),\n"
    "each read with 5 R + 4 slices of margin below and above (--slab-margin-vox), written into\n"
    "the labels file slab by slab. The labels are the same, voxel for voxel and number for\n"
    "number, as in one piece; a grain that reaches past a margin is an error (exit 2) naming\n"
    "--slab-margin-vox.\n"
    "Under the limit, or without it, the whole scan is segmented at once, as always.\n\n"
    "Examples:\n"
    "  tomograin segment scan.h5 -o labels.h5 --voxel-um 12.3            (R from 1360 um grains)\n"
    "  tomograin segment scan.tif -o labels.h5 --grain-radius-vox 20 --h 2\n"
    "  tomograin segment scan.h5 -o labels.h5 --grain-radius-vox 20 --threshold otsu --no-lines\n"
    "  tomograin segment scan.tif -o labels.h5 --grain-radius-vox 20 --threshold local   (cupping)\n"
    "  tomograin segment scan.tif -o labels.h5 --grain-radius-vox 20 --fov-radius-vox 600\n"
    "  tomograin segment big.h5 -o labels.h5 --voxel-um 12.3 --memory-limit 16GiB   (2048^3: ~8 slabs)",
    [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<tg::app::SegmentJob>();
  sub->add_option("input", o->in, "Grey scan (.tif/.tiff, folder, .json sidecar, .h5[:/dataset]); uint16 or float32")
      ->required();
  sub->add_option("-o,--output", o->out, "Labels output, .h5[:/dataset] (default dataset /labels) or TIFF")->required();
  sub->add_option("--summary", o->summary, "JSON summary path (default: OUTPUT with .segment.json)");
  tg::app::add_voxel_option(sub, o->voxel_um);
  sub->add_option("--grain-radius-vox", o->grain_radius_vox,
                  "Expected grain radius in voxels (overrides --grain-diameter-um)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--grain-diameter-um", o->grain_diameter_um,
                  "Expected grain diameter in micrometres, used with the voxel size (study: 1360)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--threshold", o->threshold,
                  "moments (Tsai) | auto (midpoint where the noise allows it, else moments) | otsu | manual | "
                  "local (moments per block, for uneven brightness) | midpoint (halfway between the void and solid "
                  "peaks)")
      ->capture_default_str();
  sub->add_option("--local-window-vox", o->seg.local_window_vox,
                  "Block edge of --threshold local in voxels (default 4 R, at least 32); implies --threshold local")
      ->check(CLI::Range(int64_t(2), int64_t(1) << 30));
  sub->add_flag("--no-fov", o->no_fov, "Do not look for a circular field of view (constant outside)");
  sub->add_option("--fov-radius-vox", o->seg.fov.radius_vox,
                  "Radius of the circular field of view in voxels (replaces the detection)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--fov-centre-vox", o->fov_centre, "Centre Y,X of the field of view (default: the slice centre)")
      ->delimiter(',')
      ->expected(2);
  sub->add_option("--manual-value", o->manual, "Grey level for --threshold manual (voxels above are solid)")
      ->check(CLI::Range(0, 65535));
  sub->add_flag("--no-pores", o->no_pores, "Do not fill enclosed pores");
  sub->add_option("--pore-max-vox", o->seg.pore_max_volume_vox,
                  "Largest pore filled, voxels (default: 2 % of (4/3) pi R^3)");
  sub->add_option("--pore-min-sphericity", o->seg.pore_min_sphericity,
                  "Least sphericity 36 pi V^2/A^3 of a filled pore, 0..1")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  sub->add_option("--h", o->seg.h, "Marker depth (h-maxima dynamic) in voxels (default: max(0.5, 0.035 R))");
  sub->add_option("--connectivity", o->seg.connectivity, "Markers and watershed neighbourhood: 6, 18 or 26")
      ->capture_default_str();
  sub->add_flag("--no-lines", o->no_lines, "Touching grains touch in the labels (no void line between them)");
  sub->add_option("--buckets-per-voxel", o->seg.buckets_per_unit, "Watershed distance quantisation, levels per voxel")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag("--no-grey-evidence", o->no_grey_evidence,
                "Decide from the solid mask alone (no dim/bright grading of the solid)");
  sub->add_option("--bright-fraction", o->seg.bright_fraction,
                  "Solid darker than t + f (mean solid grey - t) is dim, f in 0..1; a merge's interface is "
                  "bright past t + f (the two pieces' mean grey - t)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  sub->add_option("--bright-sigmas", o->seg.bright_sigmas,
                  "...and at least this many noise sigmas below the solid's peak grey (not the merge's test: "
                  "it weighs a whole interface, which noise cannot dim)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--pore-shell", o->seg.pore_shell_vox,
                  "Dim voxels within this many voxels of a filled pore are bright (its blurred shell; left dim, "
                  "a shell reaching the grain's surface parts the grain in the distance map); 0: off")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  sub->add_flag("--no-merge", o->no_merge, "Do not merge over-segmented pieces");
  sub->add_option("--merge-ratio", o->seg.merge_ratio,
                  "Merge when the shared interface >= ratio * pi r^2 (r: smaller piece's equivalent radius)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_flag("--no-split", o->no_split,
                "Do not split labels whose smoothed grey holds two bright cores parted by a darker sheet (two "
                "fragments whose gap blur and noise bridged)");
  sub->add_flag("--no-face-caps", o->no_face_caps,
                "Do not look for grains cut by a face of the scan whose thin cap the watershed gave to a neighbour "
                "(two distance maxima in a label's footprint on the face parted by a dim contact, or one whose "
                "label goes on behind the cap past a dim layer into a grain); runs with the split repair");
  sub->add_flag("--no-thin-pieces", o->no_thin_pieces,
                "Do not give a label of their own to thin pieces pressed on a grain (a chip: thinner than twice the "
                "opening radius, touching the rest of its label by under a fifth of its voxels), nor put back "
                "together the pieces of thin walls (shells) the watershed cut; runs with the split repair");
  sub->add_option("--thin-piece-radius-vox", o->seg.thin_piece_radius_vox,
                  "Radius of the ball whose opening keeps a grain's body and drops thin pieces, voxels (0: max(3, "
                  "0.15 x the grain radius))")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_flag("--no-grain-levels", o->no_grain_levels,
                "Do not raise grains darker than the rest to the solid's grey level before the threshold (by default "
                "this runs where the grains differ in brightness: the summary's grain_levels)");
  sub->add_flag("--no-face-slivers", o->no_face_slivers,
                "Do not let labels lying within 2 voxels of a scan face (grains the face cuts near their edge: "
                "all partial volume) take the unlabelled voxels beside them above half their own contrast over the "
                "void grey");
  sub->add_flag("--keep-noise-specks", o->keep_noise_specks,
                "Keep labels whose mean grey says they are void noise lifted over the threshold (by default such "
                "specks are cleared: noise_specks.hpp, the summary's noise_specks)");
  sub->add_option("--speck-z", o->seg.speck_z,
                  "A label is noise while its mean grey stands fewer than this many standard errors above what "
                  "void noise over the threshold gives (larger: clears more)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--split-depth-sigmas", o->seg.split_depth_sigmas,
                  "A piece's smoothed peak must stand this many smoothed-noise sigmas above the sheet between "
                  "pieces (blind scans: 4 split an intact grain, 6-9 gave the same labels)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--split-depth-sigmas-correlated", o->seg.split_depth_sigmas_correlated,
                  "...this many where the noise is correlated (the void's smoothed noise over 1.8 x white noise's, "
                  "as a reconstruction filter leaves it; reported as split.noise_correlation)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--split-min-depth-contrast", o->seg.split_min_depth_contrast,
                  "...and at least this share of (solid peak - threshold) grey levels above it (the floor that "
                  "keeps a scan with little noise from splitting at every pore and bump)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  sub->add_option("--split-min-piece", o->seg.split_min_piece_fraction,
                  "Smallest piece the split repair cuts off, as a share of the label's voxels (and >= 27 voxels)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  sub->add_option("--split-smoothing-vox", o->seg.split_smoothing_vox,
                  "Gaussian sigma, voxels, of the grey the split repair reads; 0: 0.7 (keeps chips 2-3 voxels thin) "
                  "unless the noise needs 1 (the depth, 6 sigmas of the smoothed noise, would pass half the solid's "
                  "height above the threshold: CNR under ~7)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--min-size", o->seg.min_size_vox, "Smallest label kept, voxels")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--memory-limit", o->memory_limit,
                  "Memory to stay under, e.g. 16GiB, 512MiB, 2G or a byte count. A scan whose segmentation needs more "
                  "(~8 B/voxel) is segmented slab by slab (its slices read a slab at a time), with the same labels")
      ->type_name("SIZE");
  sub->add_option("--slab-margin-vox", o->slab_margin_vox,
                  "Slices read below and above each slab's core (default 5 R + 4, rounded up to 16)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--compress", o->compression, "HDF5 deflate level 0-9")->check(CLI::Range(0, 9))->capture_default_str();
  return [o] { return tg::app::run_segment(*o); };
}}};
}  // namespace cmd_segment

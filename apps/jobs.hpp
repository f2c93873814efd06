// The jobs behind `segment`, `measure` and `psd`, callable from other
// commands: `analyse` and `demo` chain them on files exactly as a user would
// on the command line, so there is one implementation of each step.
#pragma once
#include <string>
#include <vector>

#include "core/volume.hpp"
#include "segmentation/segment.hpp"

namespace tg::app {

// tomograin segment: grey scan -> /labels (u32) + JSON summary.
struct SegmentJob {
  std::string in, out, summary, threshold = "moments";
  double voxel_um = 0, grain_radius_vox = 0, grain_diameter_um = 1360.0;
  int manual = -1;
  tg::SegmentOptions seg;
  bool no_pores = false, no_lines = false, no_merge = false, no_grey_evidence = false, no_split = false,
       no_face_caps = false, no_thin_pieces = false, no_face_slivers = false,
       no_grain_levels = false;
  bool keep_noise_specks = false;
  bool no_fov = false;                // --no-fov: no field-of-view detection
  std::vector<double> fov_centre;     // --fov-centre-vox Y,X (empty: the slice centre)
  int compression = 1;
  // When set (analyse), the labels are moved here after they are written,
  // so that the next step need not read and decompress them again.
  Volume<uint32_t>* keep_labels = nullptr;
  std::string memory_limit;           // --memory-limit (empty: none); slabs when the scan does not fit
  int64_t slab_margin_vox = -1;       // --slab-margin-vox (< 0: 5 R + 4)
};
int run_segment(SegmentJob& job);

// tomograin measure: label volume -> particle table (CSV and/or HDF5).
struct MeasureJob {
  std::string in;
  std::vector<std::string> out;
  std::string feret = "60";
  std::string sizing = "feret";
  double limit_mm = 0.2;
  double face_offset = 0.3;
  bool box = false;          // CGAL's oriented box (obb_* columns): only when asked, it dominated the run time
  bool no_box = false;       // the old flag, accepted and without effect (the box is off unless `box`)
  bool no_contacts = false;
  bool surface = false;      // surface_mm2 + sphericity (measure/surface.hpp)
  bool convex = false;       // convex_volume_mm3 + solidity (CGAL hull)
  // Optional column groups by name (coordination, surface, sphericity,
  // convex, solidity, obb): when given, exactly these are computed and the
  // flags above are ignored.
  std::vector<std::string> columns;  // skip the coordination column (measure/contacts.hpp)
  int threads = 0;
  unsigned seed = 42;
  double voxel_um = 0;
  // The grey scan the labels came from (any format segment reads): the
  // volumes become partial-volume estimates (measure/grey_volume.hpp).
  std::string grey;
  // With grey: every particle's band read with the scan's solid level, not
  // its own (measure/grey_volume.hpp "Local solid level").
  bool grey_global_level = false;
  // When set (analyse), these labels (read from `in` by an earlier step) are
  // measured instead of reading `in` again; `in` still names them.
  const Volume<uint32_t>* labels = nullptr;
  // --memory-limit (empty: none): labels (and grey scan) in HDF5 that do not
  // fit are measured slab by slab (measure/measure_chunked.hpp).
  std::string memory_limit;
};
int run_measure(const MeasureJob& job);

// A grey scan as u16, as segment reads it: float32 normalised (auto range,
// printed), u8 widened; `top` is the input's saturation level in u16 grey
// (255 for u8). InputError for a label (u32) volume.
Volume<uint16_t> read_grey(const std::string& in, double voxel_um, int& top);

// The u32 label volume of `in` (an .h5 without a dataset name: its /labels),
// with --voxel-um applied; InputError when it has no voxel size.
Volume<uint32_t> read_labels(const std::string& in, double voxel_um);

// tomograin psd: particle tables of one or more stages -> gradings and summaries.
struct PsdJob {
  std::vector<std::string> in;
  std::vector<std::string> names;  // shown in the summary's "file" column; empty = the input paths
  std::string out, summary;
  std::vector<double> sieves, fr_bins, ar_bins;
  bool exclude_below = false, exclude_border = false;
  double hardin_cut = 0.074, fractal = 2.6, einav_dmin = 0;
};
int run_psd(PsdJob job);

}  // namespace tg::app

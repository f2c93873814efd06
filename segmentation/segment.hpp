// The whole image pipeline, one function for both worlds (scans and
// voxelised DEM snapshots, ../shared/DESIGN.md "Data flow"):
//
//   grey u16 -> threshold -> solid mask -> pore filter -> distance map
//            -> h-maxima markers -> watershed (lines) -> merge repair
//            -> consecutive labels with a size filter -> labels u32
//
// Each stage is its own header (threshold, pore_filter, distance_transform,
// markers, watershed, merge_labels, connected_components), with the method
// and its reference there; this file only chains them and records what was
// chosen, how long each stage took and the peak memory.
//
// Memory (why the stages are ordered and buffers reused this way): the grey
// volume (2 B/voxel) is needed only for the histogram and the mask; the
// rvalue overload writes the u8 mask over the grey volume's own storage.
// The pore filter works on runs of void voxels (no label volume). Then the
// float distance map (4 B) is made; the mask goes (the map is 0 exactly
// on the void), the u32 markers (4 B) come; the flood levels (u8) are
// written over the map's storage, whose spent 3 B/voxel are given back;
// the watershed labels and the merge are in place in the markers' volume.
// At most two 4-byte volumes live at once: 8 B/voxel at peak, plus the
// frontier queue (4 B per queued voxel, a small fraction of the volume)
// and the process itself. Measured (peak RSS of the whole `tomograin
// segment` process, data_synth zeolite stage 4): 9.1 B/voxel at 256^3
// (the process is ~1 B/voxel at that size), 8.2 B/voxel at 512^3. A
// 1220^3 scan (1.8e9 voxels) thus needs ~15 GB.
// No 64-bit label or index volumes.
//
// Distances are in units of the smallest voxel edge (anisotropic voxels
// use the ratios of Geometry::voxel_size_m; unknown size = isotropic).
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/volume.hpp"
#include "segmentation/field_of_view.hpp"
#include "segmentation/local_threshold.hpp"
#include "segmentation/merge_labels.hpp"
#include "segmentation/pore_filter.hpp"
#include "segmentation/threshold.hpp"
#include "segmentation/watershed.hpp"

namespace tg {

// A physical grain radius in the distance map's unit, the finest voxel edge
// (an anisotropic scan's z edge may be the finest, not x). UsageError when
// the geometry has no voxel size.
double grain_radius_in_voxels(double radius_m, const Geometry& geometry);

struct SegmentOptions {
  // Expected grain radius in voxels of the finest edge (grain_radius_in_voxels):
  // the scale the defaults below derive from.
  double grain_radius_vox = 20.0;

  ThresholdMethod threshold = ThresholdMethod::moments;
  int manual_threshold = -1;  // grey level for ThresholdMethod::manual (voxels above are solid)
  int64_t local_window_vox = 0;  // ThresholdMethod::local: block edge; 0: 4 R (default_local_window)

  // Which voxels are data (field_of_view.hpp): the circular field of view
  // (detected from a constant outside, given, or none) and the input's top
  // grey level, whose saturation is screened (255 for 8-bit scans).
  FovOptions fov;
  int saturation_level = 65535;

  bool fill_pores = true;
  int64_t pore_max_volume_vox = -1;  // < 0: 2 % of the expected grain volume (PoreFilterOptions::from_grain_radius)
  double pore_min_sphericity = 0.5;

  // Marker depth (h-maxima dynamic), distance units. 0.7 voxels: above the
  // staircase ripples of a digital distance map (< 0.5), below the dynamic of
  // thin fragments (chips of 3-8 voxels) joined to their parent by blur
  // bridges. Measured on data_synth zeolite stages at R = 22.7 voxels:
  // h = 0.7 -> F1 0.980/0.989 (broken/intact); h = 2.3 (0.1 R) -> 0.91/0.98.
  double h = 0.7;
  int connectivity = 26;
  bool watershed_lines = true;
  double buckets_per_unit = 4.0;

  bool merge = true;
  double merge_ratio = 1.0;  // MergeOptions::ratio

  int64_t min_size_vox = 8;  // labels smaller than this become void (after merging)

  // Resolved values (derived defaults filled in), as the pipeline will use them.
  SegmentOptions resolved() const;
};

struct SegmentResult {
  Volume<uint32_t> labels;  // 0 void, 1..count particles, geometry of the input
  ThresholdResult threshold;
  double solid_fraction = 0;  // after thresholding, before pore filling; of the voxels inside the field of view
  FieldOfView fov;            // inactive when the whole volume is data
  LevelScreen levels;         // pre-masked zeros, saturation
  LocalThreshold local;       // ThresholdMethod::local only
  PoreFilterOptions pore_criteria;
  PoreFilterResult pores;
  double h = 0;
  uint32_t markers = 0;
  double buckets_per_unit = 0;  // watershed levels per distance unit actually used (see quantise_levels)
  MergeResult merge;
  uint32_t count = 0;       // final labels
  int64_t dropped = 0;      // labels removed by min_size_vox
  std::vector<std::pair<std::string, double>> stage_seconds;
  int64_t peak_rss_bytes = 0;
  std::vector<std::string> notes;  // special cases met (two grey levels, no void, ...)
};

// Runs the chain; the rvalue overload takes the grey volume and writes the
// mask over it (no second volume). Throws InputError for degenerate input
// (e.g. a constant volume) and UsageError for invalid options.
SegmentResult segment(const Volume<uint16_t>& grey, const SegmentOptions& opt);
SegmentResult segment(Volume<uint16_t>&& grey, const SegmentOptions& opt);

// From a solid mask on (threshold already applied; the mask is consumed).
SegmentResult segment_mask(Volume<uint8_t> solid, const SegmentOptions& opt);

// The summary as JSON text (options, threshold, pores, markers, merges,
// labels, time per stage, peak memory).
std::string summary_json(const SegmentResult& r, const SegmentOptions& opt);

}  // namespace tg

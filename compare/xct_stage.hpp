// The experiment's side of one loading stage: a grey scan (segmented with the
// comparison's SegmentOptions, exactly the DEM's imaged path), a label volume
// (measured as is) or a particle table (tomograin measure's CSV), with what
// the file says about itself (synthetic provenance, strain, truth).
#pragma once
#include <filesystem>
#include <limits>
#include <optional>
#include <string>

#include "compare/comparison.hpp"
#include "compare/imaging_estimate.hpp"
#include "compare/series.hpp"

namespace tg::compare {

struct XctStage {
  Series s;
  double strain = std::numeric_limits<double>::quiet_NaN();  // from synth provenance, when present
  bool synthetic = false;
  Geometry geometry;  // voxel size unknown (0) for particle-table inputs
  std::optional<GreyEstimate> grey;
  Volume<uint32_t> labels;  // the stage's labels (segmented or read), for tracking; empty for tables
  Volume<uint16_t> scan;    // the grey scan, for the tracker's rotations (CompareOptions::track_rotations)
};

// The segmentation options both worlds share at one voxel size: the scale is
// the option, else the first snapshot's median particle radius in voxels.
SegmentOptions segment_options(const CompareOptions& opt, double median_r_m, double voxel_m);

// Loads, segments (grey scans) and measures one stage; writes its mid-slices
// (grey and labels) to slices_dir as STEM_experiment_{grey,labels}_*.npy.
XctStage load_xct_stage(const std::string& path, const CompareOptions& opt, double median_r_m,
                        const std::filesystem::path& slices_dir, const std::string& stem);

// Fraction of the initial grains that are broken, from a data_synth truth
// table (kind, parent): distinct parents of fragment rows over distinct
// parents of all rows; NaN without those columns.
double broken_from_truth(const Table& truth);

}  // namespace tg::compare

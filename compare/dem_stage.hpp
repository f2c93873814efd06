// The DEM's side of the comparison: which snapshots, at which strains, and
// one snapshot voxelised at a stage's voxel size and measured twice —
// `ideal` (its truth labels) and `imaged` (segmented exactly like a scan).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "compare/comparison.hpp"
#include "compare/series.hpp"
#include "compare/stage_matching.hpp"
#include "core/sphere_table.hpp"

namespace tg::compare {

struct DemInputs {
  std::vector<std::string> snapshots;  // sphere tables (core/sphere_table.hpp)
  std::vector<double> strains;         // one per snapshot; NaN = unknown (matched by order)
  Curve history;                       // empty without a history
};
// From the run folder (dem/run_folder.hpp: its snapshot index and history),
// or from the explicit snapshot list (+ strains) of `in`.
DemInputs load_dem_inputs(const CompareInputs& in);

// Median equal-volume radius of the particles of a sphere table (metres) and
// their count: the segmentation scale and the initial grain count.
struct ParticleScale {
  double median_radius_m = 0;
  int64_t particles = 0;
};
ParticleScale particle_scale(const SphereTable& s);

// Mean coordination of a snapshot's particles counted from the spheres
// themselves (the DEM's exact contacts): two particles touch when a sphere of
// one and a sphere of the other are closer than the sum of their radii plus
// `gap_tolerance` × the smaller radius; contacts with walls do not count
// (walls are not particles). A cell grid of the largest diameter: O(n).
double sphere_coordination(const SphereTable& s, double gap_tolerance = 1e-3);

struct DemStage {
  Series ideal, imaged;  // imaged empty when the imaged path is off
  int64_t particles = 0; // particles voxelised
  double exact_coordination = 0;  // sphere_coordination of the snapshot
};
// Voxelises `snapshot` at voxel_m with `imaging` (grey levels and noise),
// measures the truth labels and, when opt.imaged_path, segments and measures
// the grey scan with `so`; writes the mid-slices (STEM_dem_*).
DemStage image_snapshot(const std::string& snapshot, double voxel_m, const synth::ImagingOptions& imaging,
                        const std::string& imaging_from, const CompareOptions& opt, const SegmentOptions& so,
                        const std::filesystem::path& slices, const std::string& stem);

}  // namespace tg::compare

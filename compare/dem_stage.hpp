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

// The DEM's exact contacts, from the spheres themselves: every pair of
// spheres of different particles closer than the sum of their radii plus
// `gap_tolerance` × the smaller radius (the sphere–sphere contacts the DEM
// itself resolves; walls are not particles). Normal (z, y, x): unit vector
// from the centre of the sphere of `a` to that of `b`. A cell grid of the
// largest diameter: O(n). Listed by sphere index, so deterministic.
struct SphereContact {
  int64_t a = 0, b = 0;  // particle ids, a < b
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};
std::vector<SphereContact> sphere_contacts(const SphereTable& s, double gap_tolerance = 1e-3);

// The exact series of compare/fabric.hpp: the fabric of every sphere contact,
// the coordination (distinct touching particles: two particles touching
// through several sphere pairs count once) by quartile of the particles'
// equal-volume diameter (from the sphere volumes, in mm; tangent fragment
// spheres do not overlap, so the sum of their volumes is exact). Its mean
// coordination: mean_coordination(by_size).
ContactSeries exact_contact_series(const SphereTable& s, double gap_tolerance = 1e-3);

struct DemStage {
  Series ideal, imaged;  // imaged empty when the imaged path is off
  int64_t particles = 0; // particles voxelised
  double exact_coordination = 0;  // mean coordination of the snapshot's particles (exact.by_size)
  ContactSeries exact;            // the snapshot's own contacts (exact_contact_series)
  measure::GradingSample exact_shapes;  // every particle's shape from its spheres (exact_shape_sample)
  // Kept only when asked (keep_labels): for the DEM's lineage and the tracker
  // run on the imaged path (compare/dem_lineage.hpp).
  Volume<uint32_t> truth_labels, imaged_labels;
  std::vector<int64_t> particle_of_label;  // truth label -> particle id (index 0 unused)
};
// The shape of every DEM particle straight from its spheres: no voxels, no
// detection limit. A particle is the convex hull of its spheres (the body a
// fragment stands for, as voxelise's default cluster_body images it); Dmax
// and Dmin by measure's exact Feret mode on that hull, with the particle
// table's tie rule at 1 % of Dmax (each sphere's surface
// sampled at 256 points, pushed out to the sphere's volume: calipers within
// -0.1 % .. +0.6 % of its radius; a capsule's volume +0.3 %, FR +0.004), Dmed, FR and
// AR by measure::fill_sizing from the hull's volume, as a scan's particle
// table has them. A lone sphere is FR = AR = 1 exactly. size_mm is Dmed,
// mass the hull volume (mm^3), deq_mm from the spheres' volume. Why: the
// study's DEM shape classes at the end (78 % FR >= 0.9, 80 % AR < 2) count
// the spheres that bond breakage set free, most of them far below a scan's
// detection limit, which the imaged series (dem_ideal) cannot resolve
// (bench/dem/RESULTS.md, "Shape classes of every DEM particle").
measure::GradingSample exact_shape_sample(const SphereTable& s);

// Voxelises `snapshot` at voxel_m with `imaging` (grey levels and noise),
// measures the truth labels and, when opt.imaged_path, segments and measures
// the grey scan with `so`; writes the mid-slices (STEM_dem_*). keep_labels:
// the label volumes stay in the result.
DemStage image_snapshot(const std::string& snapshot, double voxel_m, const synth::ImagingOptions& imaging,
                        const std::string& imaging_from, const CompareOptions& opt, const SegmentOptions& so,
                        const std::filesystem::path& slices, const std::string& stem, bool keep_labels = false);

}  // namespace tg::compare

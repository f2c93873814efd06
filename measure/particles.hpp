// The particle table: label_stats + Feret sizing (+ hull, box, surface, contacts)
// for every label of a volume, as records and as a tomograin Table with the
// column names the CLI and compare/ use.
//
// Pipeline per particle (independent, so OpenMP shares particles out with a
// dynamic schedule; each particle's numbers depend only on its own voxels, so
// the table is identical for any thread count):
//   boundary voxels -> caliper_points (face-offset convention, feret.hpp)
//   -> Feret sampled at N directions straight on those points (no hull:
//      a point set's widths are its hull's), or, for the exact mode, the
//      oriented box (CGAL heuristic) and the convex volume, convex_hull
//      first (CGAL; ~10x the sampled path's cost per particle, and the box
//      ~100x: bench/measure/RESULTS.md)
//   -> optional: surface area + sphericity (surface.hpp), coordination
//      (contacts.hpp: three scans of the whole volume).
// Dmed = 6 V / (pi Dmax Dmin) (the ellipsoid with axes Dmax, Dmin, Dmed has
// the particle's volume); FR = Dmin / Dmed; AR = Dmax / Dmin. With
// sizing = obb the three columns are the oriented box's sorted edges instead
// (the reference study's "smallest box circumscribed to the particle").
#pragma once
#include <string>
#include <vector>

#include "core/table.hpp"
#include "measure/contacts.hpp"
#include "measure/grey_volume.hpp"
#include "measure/hull.hpp"
#include "measure/label_stats.hpp"
#include "measure/surface.hpp"

namespace tg::measure {

enum class Sizing { feret, obb };

struct ParticleOptions {
  LabelStatsOptions stats;
  int feret_directions = 60;  // the reference study's 60 orientations
  bool feret_exact = false;   // exact hull diameter / min widths instead of sampled directions
  // Dmax candidates within this many voxels of Dmax (feret.hpp's tie rule,
  // both modes); 0 = the study's literal single-direction definition.
  double tie_tolerance_voxels = 0.5;
  Sizing sizing = Sizing::feret;  // which definition fills d_max / d_med / d_min, fr, ar
  double face_offset = 0.3;   // hull point convention, see feret.hpp
  bool oriented_box = true;   // also run CGAL's oriented box (obb_* columns)
  OrientedBoxOptions obb;
  bool convex = false;        // convex_volume_mm3 + solidity (needs the CGAL hull)
  // The CGAL hull is built only for the exact mode, the oriented box and
  // `convex`; sampled calipers read the hull points directly (same widths).
  // force_hull builds it anyway (the fast path's test and benchmark).
  bool force_hull = false;
  bool surface = false;       // surface area + Wadell sphericity (measure/surface.hpp; costs ~10x the Feret step)
  SurfaceOptions surface_opt;
  bool contacts = false;      // also find contacts (measure/contacts.hpp): the coordination column
  // The grey scan the labels were segmented from (same shape), or null.
  // When given, each particle also gets the partial-volume estimate of
  // measure/grey_volume.hpp (levels from `grey_levels`) as grey_volume_m3,
  // which the table reports as volume_mm3 and d_eq_mm (label_volume_mm3
  // keeps the label's). Dmed, FR, solidity and sphericity keep the label's
  // own volume: its calipers, hull and surface come from the same voxels,
  // and a segmentation that shrinks a grain shrinks both alike (the
  // grey volume over the shrunken calipers read Dmed 7 % high on
  // data_synth spheres of radius 8 voxels: tests/apps/analyse_test.sh).
  const VolumeView<const uint16_t>* grey = nullptr;
  // Or, instead, the scan read window by window (grey_volume.hpp): the same
  // volumes with ~256 MiB of it in memory instead of the whole scan.
  const GreySlabSource* grey_slabs = nullptr;
  GreyVolumeOptions grey_levels;
  ContactOptions contact;
  int threads = 0;            // 0 = OpenMP default
};

struct Particle {
  LabelStats stats;
  FeretResult feret;
  OrientedBox box;  // dims 0 when oriented_box is off
  int hull_vertices = 0;  // 0 when no hull was built (sampled mode without box or convex)
  int coordination = -1;  // contacts with other labels; -1 when contacts were not asked for
  double convex_volume_m3 = -1;  // of the Feret hull (face-offset points, see below); -1 when not asked for
  double solidity = -1;          // min(1, V / convex volume); -1 when not asked for
  double surface_m2 = -1;       // -1 when not asked for
  double sphericity = -1;       // Wadell; -1 when not asked for
  double d_max_m = 0, d_med_m = 0, d_min_m = 0, fr = 0, ar = 0;  // per the chosen sizing
  bool fr_clamped = false;  // Dmin / Dmed was > 1 (non-convex particle): fr set to 1
  double grey_volume_m3 = -1;  // ParticleOptions::grey only (measure/grey_volume.hpp); -1 otherwise
  // The volume the table reports: the grey-level one where there is one, else the label's.
  double volume_m3() const { return grey_volume_m3 >= 0 ? grey_volume_m3 : stats.volume_m3; }
};

std::vector<Particle> measure_particles(const VolumeView<const uint32_t>& labels, const ParticleOptions& opt = {});
// The per-particle part of measure_particles (hull, calipers, box, sizing)
// from label_stats' result with its boundary voxels, and, with a grey scan,
// the grey volumes in voxels aligned with ls.labels (empty: none;
// ParticleOptions::grey is not read). Contacts are not found here; surface
// areas need `labels` (the whole label volume; UsageError without it). The
// slab-by-slab path (measure_chunked.hpp) calls it with its merged sums.
std::vector<Particle> particles_from_stats(const LabelStatsResult& ls, const std::vector<double>& grey_vox,
                                           const Geometry& geometry, const ParticleOptions& opt,
                                           const VolumeView<const uint32_t>* labels = nullptr);

// Dmed, FR, AR from volume and the two calipers (NaN-free: a zero caliper
// gives 0, which cannot happen with the face-offset hull points: every voxel
// gives a 3-D hull, a single voxel an octahedron of calipers 0.3 voxel).
// Rule for FR > 1 (issue 22): Dmed = 6V/(pi Dmax Dmin) falls below Dmin on
// hollow or non-convex particles (their volume is less than the ellipsoid's
// with axes Dmax, Dmin, Dmin); on a real carbonate-sand scan 68 % of the
// particles did. FR is then clamped to 1 and fr_clamped set: the study's FR
// classes stay valid (such a particle is as "unflat" as FR can say) and the
// flag tells how many. d_med itself is not changed (the grading uses it).
void fill_sizing(Particle& p, Sizing sizing);

// Columns: label, voxels, volume_mm3 (Particle::volume_m3()), cx_mm, cy_mm, cz_mm, d_eq_mm, d_max_mm,
// d_min_mm, d_med_mm, fr, ar, fr_clamped, obb_max_mm, obb_med_mm, obb_min_mm,
// touches_border, below_limit, then feret_dmax_mm, feret_dmin_mm,
// feret_dmin_any_mm, hull_vertices, bbox (voxel indices) and the principal
// moments of inertia (mm^5), the equivalent ellipsoid's full axes
// ell_d1_mm >= ell_d2_mm >= ell_d3_mm and major axis ell_axis1_z/y/x
// (label_stats.hpp), then convex_volume_mm3 and solidity, surface_mm2 and
// sphericity when asked for, `coordination` when contacts were found, and
// label_volume_mm3 when volume_mm3 is the grey-level volume.
//
// Convex volume: the volume of the hull the Feret calipers use (points
// lambda/2 = 0.15 voxel beyond the boundary voxels' centres, feret.hpp).
// That hull's calipers are unbiased on spheres on average (mean caliper
// +0.05 % at radius 20), yet its volume reads ~1 % less than the voxels' on
// spheres of radius 20 (particles_test; the hull cuts the staircase's
// outer corners, which carry volume the calipers do not see). Solidity =
// V / convex volume, clamped to 1: a convex particle reads 1, a concave
// one less (a hemispherical shell with inner radius 0.7 R: 0.66, truth
// 0.657).
Table particle_table(const std::vector<Particle>& particles);

// Volume of a 3-D hull (0 for a flat one): tetrahedra from the vertices' mean.
double hull_volume(const ConvexHull& hull);

// "feret-60", "feret-exact" or "obb": the definition behind d_max/d_min/d_med.
std::string sizing_name(const ParticleOptions& opt);

}  // namespace tg::measure

// Voxelising a DEM packing: spheres (metres, cylinder axis z, centred on
// x = y = 0, bottom platen at z = 0), grouped into particles by a particle id
// (a bonded cluster is one particle), become what a CT scan of them would be:
//   1. a grid: voxel size given; field of view = the spheres' bounding box
//      plus a margin (default), or the oedometer cylinder (square in x, y of
//      the cylinder's diameter, z from the bottom platen to the top sphere);
//   2. the exact partial-volume solid fraction and the u32 truth labels, one
//      label per particle, by data_synth's renderer (data_synth/render.hpp:
//      every voxel's covered fraction from the exact sphere–cube integral).
//      A cluster whose member spheres overlap is a data_synth `cluster`
//      particle (the union, so overlaps count once; its rim voxels pay for
//      the renderer's octree rule). A cluster whose members do not overlap
//      (the DEM fragment template: tangent spheres; allowed penetration
//      `member_overlap` × the smaller radius) is rendered as its separate
//      spheres, whose coverages the renderer sums exactly as the union's,
//      then relabelled to the one particle: the same solid fraction to
//      within the lens volumes of the allowed penetrations (≈ π r δ² / 2
//      per pair, < 2e-6 of a sphere's volume at δ = 1e-3 r) and ~10–50×
//      faster at coarse voxels. Labels follow data_synth's rule (largest
//      coverage, 0 where solid < 0.5), with a member sphere's coverage in
//      place of its cluster's in the rare voxel shared by two particles;
//      Option cluster_body (default hull): a cluster is first replaced by
//      the BODY it stands for, the convex hull of its member spheres, so
//      that a DEM fragment (17 tangent spheres standing for a half grain)
//      images as one solid body, as the experiment's fragments do, not as a
//      bunch of grapes with dark necks that segmentation cuts apart. The
//      hull is rendered as one data_synth piece (hull_body below): the
//      members' enclosing sphere ∩ support half-spaces whose normals are
//      the exact facet normals, samples of the cones' normals and a lattice
//      of `hull_directions`, an outer polytope within +0.2 % of the hull's
//      volume for the template (tests/compare/voxelise_test.cpp). Ideal
//      labels, truth table and grey all use the same body. The template's
//      hull is 0.812 of its nominal half sphere (the mother cut by the
//      plane) and 1.502 × the sum of its member spheres (the DEM's mass,
//      0.540 of the half sphere). Lone spheres are unchanged;
//      cluster_body = members renders the member spheres as above.
//   3. the grey u16 scan by data_synth's imaging model (imaging.hpp: grey
//      levels, Gaussian PSF, noise), default levels or estimated from an
//      experimental scan (compare/imaging_estimate.hpp).
// Nothing here re-implements rendering or imaging: it maps DEM tables to
// data_synth particles and a grid, then calls data_synth.
// Cost: that of the renderer, O(Σ bbox voxels) + O(surface voxels · ~1 µs),
// and of the imaging model, O(N · (8σ+1)); memory 8 B/voxel (solid + labels)
// plus 2 B/voxel for the grey output.
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/sphere_table.hpp"
#include "core/table.hpp"
#include "core/volume.hpp"
#include "data_synth/geometry.hpp"
#include "data_synth/imaging.hpp"
#include "data_synth/render.hpp"

namespace tg::compare {

enum class FieldOfView { spheres, cylinder };
// How a cluster (a particle of several spheres) is imaged: the convex hull of
// its members (the body a DEM fragment stands for) or the member spheres.
enum class ClusterBody { hull, members };
ClusterBody cluster_body_from_name(const std::string& name);  // "hull" | "members"; else UsageError
// The --cluster-body help of `voxelise` and `compare` (one text, two commands).
inline constexpr const char* kClusterBodyHelp =
    "How a DEM cluster (a fragment of bonded spheres) is imaged: hull = the convex hull of its spheres, one "
    "solid body like the experiment's fragments (ideal and imaged alike; 1.5x the spheres' volume for the "
    "study's fragment, 0.81 of its half grain); members = the separate spheres, whose necks segmentation "
    "cuts apart (several labels per fragment)";

struct VoxeliseOptions {
  double voxel_m = 0;                  // voxel edge, metres (required, > 0)
  FieldOfView field = FieldOfView::spheres;
  double margin_vox = 3;               // void voxels added around the field on every side
  double cylinder_diameter_m = 15e-3;  // field = cylinder: the reference study's Ø15 mm cell
  synth::ImagingOptions imaging;       // grey levels, PSF, noise (data_synth defaults)
  bool grey = true;                    // false: skip the imaging model (labels only)
  bool truth = false;                  // data_synth's truth table (exact per-particle volume,
                                       // centroid, Feret); costs ~0.1 s per 17-sphere cluster
  double member_overlap = 1e-3;        // clusters whose members penetrate less than this × the
                                       // smaller radius render as separate spheres (see above);
                                       // < 0: always render clusters as exact unions
  synth::RenderOptions render;         // renderer accuracy knobs (data_synth defaults)
  ClusterBody cluster_body = ClusterBody::hull;
  int hull_directions = 64;            // lattice directions of a hull body's support planes (>= 4)
  int hull_depth = 0;                  // octree levels for the voxels a hull body's planes cut (replaces
                                       // render.depth when clusters are hulls; lone spheres never use it):
                                       // 0 = one 8×8 chord rule per voxel, the template's volume within
                                       // 1e-5 of depth 3's at ~1/50 of its cost (docs/compare.md)
};

struct Voxelised {
  Volume<uint16_t> grey;    // imaged scan (empty when options.grey is false)
  Volume<uint32_t> labels;  // truth labels 1..particles, 0 = void
  // Input particle id of label l at index l (index 0 unused): labels follow
  // the order in which particle ids first appear in the table.
  std::vector<int64_t> particle_of_label;
  Table truth;              // data_synth truth table + column `particle` (input id); empty unless options.truth
  int64_t clusters_union = 0, clusters_split = 0, clusters_hull = 0;  // how clusters were rendered
  double solid_fraction = 0;  // mean solid fraction of the grid (before imaging)
  int64_t saturated = 0;      // grey voxels clipped at 0 or 65535
  double render_s = 0, imaging_s = 0;
};

// The body a cluster is imaged as under ClusterBody::hull: one data_synth
// piece, the members' enclosing sphere ∩ the hull's support half-spaces
// {u·p <= max_j (u·c_j + r_j)} for `directions` unit vectors u (a Fibonacci
// lattice). Same id, kind and parent as `cluster`.
synth::Particle hull_body(const synth::Particle& cluster, int directions);

// The grid voxelise() uses (shape + geometry) for these spheres and options.
std::pair<Shape, Geometry> voxel_grid(const SphereTable& s, const VoxeliseOptions& opt);

Voxelised voxelise(const SphereTable& s, const VoxeliseOptions& opt);

// What a voxelised scan is, as JSON (the .h5's `voxelise` attribute and the
// report's provenance): input, voxel_um, shape, solid_fraction, void_grey,
// solid_grey, noise_sigma, psf_sigma_vox, imaging_from. No timings: the same
// input gives the same bytes (tests/determinism).
nlohmann::json voxelise_json(const std::string& input, const VoxeliseOptions& opt, const Voxelised& v,
                             const std::string& imaging_from);

}  // namespace tg::compare

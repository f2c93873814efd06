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
};

struct Voxelised {
  Volume<uint16_t> grey;    // imaged scan (empty when options.grey is false)
  Volume<uint32_t> labels;  // truth labels 1..particles, 0 = void
  // Input particle id of label l at index l (index 0 unused): labels follow
  // the order in which particle ids first appear in the table.
  std::vector<int64_t> particle_of_label;
  Table truth;              // data_synth truth table + column `particle` (input id); empty unless options.truth
  int64_t clusters_union = 0, clusters_split = 0;  // how clusters were rendered
  double solid_fraction = 0;  // mean solid fraction of the grid (before imaging)
  int64_t saturated = 0;      // grey voxels clipped at 0 or 65535
  double render_s = 0, imaging_s = 0;
};

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

// Scenes: everything `tomograin synth` needs to build a specimen, from a named
// preset, overridden by a strict TOML scene file and the command line.
//
// Presets (all keys below can be overridden in the TOML file):
//   spheres         box 3.2 mm, D50 0.4 mm, Cu 1.2, 128³ (25 µm voxels), no pores
//   zeolite         the reference study: Ø15 mm × 12.25 mm cylinder, D50 1.36 mm,
//                   Cu 1.07, 3 pores per grain (r = 0.06 R), field 15.006 mm
//                   (1220 × 12.3 µm); default 256³ = coarser voxels (58.6 µm)
//   zeolite-stages  zeolite at strains 0, 4.4, 7.12, 11.28, 15.48 % with 0, 15,
//                   30, 50, 70 % of the grains broken; one file per stage
//                   (PREFIX_stage0.h5 …); default 128³
//   extremes        five 64³ files: PREFIX_tiny (grains of 1–3 voxels),
//                   PREFIX_border (grains cut by every face), PREFIX_empty,
//                   PREFIX_solid (all solid), PREFIX_saturated (grey > 65535)
//
// Grid: a cube of `size` voxels of edge `voxel_um`, centred on the specimen
// axis and on the initial specimen mid-height. The field of view `field_mm`
// (default: the container width) fixes whichever of the two is not given:
// size only -> voxel = field/size (coarser voxels, whole specimen);
// voxel only -> size = ceil(field/voxel); both -> a centred crop.
//
// TOML keys (unknown keys are errors):
//   seed
//   [specimen] container ("cylinder"|"box"), diameter_mm, height_mm, box_y_mm,
//              box_x_mm, d50_mm, cu, target_fraction, pores_per_grain,
//              pore_radius_fraction, particles (CSV or H5 file: x_m,y_m,z_m,r_m
//              [,particle] as the DEM writes, or cz_vox,cy_vox,cx_vox,radius_vox)
//   [grid]     voxel_um, size, field_mm
//   [imaging]  void_grey, solid_grey, psf_sigma_vox, noise_sigma,
//              poisson_counts_per_grey, cupping, rings, ring_amplitude
//   [stages]   strains, broken (lists), gap_vox, mix_split, mix_multi,
//              mix_chip, chip_min, chip_max, motion ("stretch" | "oedometer"),
//              jitter, rotation_deg, drift, rebreak (oedometer motion:
//              data_synth/motion.hpp; it also writes PREFIX_lineage.csv, the
//              truth lineage in the columns of `tomograin track`)
//   [render]   chord_order, depth, slab
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "core/table.hpp"
#include "core/volume.hpp"
#include "data_synth/granule.hpp"
#include "data_synth/imaging.hpp"
#include "data_synth/motion.hpp"
#include "data_synth/packing.hpp"
#include "data_synth/render.hpp"

namespace tg::synth {

struct Scene {
  std::string preset = "spheres";
  uint64_t seed = 1;
  PackingOptions packing;         // lengths in mm
  int pores_per_grain = 0;
  double pore_radius_fraction = 0.06;
  std::string particles_file;     // explicit list instead of a packing
  double voxel_um = 0;            // 0 = from field/size
  int64_t size = 0;               // 0 = from field/voxel, or the preset default
  int64_t default_size = 128;
  double field_mm = 0;            // 0 = container width
  ImagingOptions imaging;
  bool stages = false;
  StageOptions stage;
  MotionOptions motion;           // stage series: "stretch" (default) or oedometer motion
  RenderOptions render;
};

Scene preset_scene(const std::string& name);  // InputError lists the presets
const std::vector<std::string>& preset_names();
void apply_config(Scene& scene, Config& cfg);  // reads every key above, then cfg.finish()

struct Grid {
  Shape shape;
  Geometry geometry;  // metres
  double voxel_mm = 0;
  Vec3 origin_mm{0, 0, 0};
};
Grid make_grid(const Scene& scene);

// Intact grains in voxel units (packing or the explicit list), pores added.
// For a stage series the packing is made in the shortest specimen.
struct Grains {
  std::vector<Particle> particles;
  Packing packing;         // statistics (empty spheres when read from a file)
  double z_bottom_vox = 0; // the bottom platen in voxel coordinates
};
Grains make_grains(const Scene& scene, const Grid& grid);

// Reads sphere lists: DEM form (core/sphere_table.hpp: x_m, y_m, z_m, r_m,
// optional `particle` grouping spheres into one particle, `cluster` read as a
// synonym), a CSV or an HDF5 snapshot, mapped through the grid by
// synth::particles_from_spheres (the mapping voxelise uses); or voxel truth
// form (cz_vox, cy_vox, cx_vox, radius_vox, optional id).
std::vector<Particle> read_particles(const std::string& path, const Grid& grid);

struct Timings {
  double packing_s = 0, render_s = 0, imaging_s = 0, truth_s = 0, write_s = 0;
};

// Renders, images and writes one specimen: HDF5 with /volume (u16), /labels (u32),
// /reconstruction (f32, when `write_float`), table /truth and a provenance
// attribute; and the truth CSV beside it (PATH with .h5 replaced by _truth.csv).
struct WriteResult {
  Timings t;
  double solid_fraction_voxels = 0;  // mean of the solid-fraction volume
  int64_t saturated = 0;
  int64_t particles = 0;
  Table truth;  // the truth table written beside the file
};
WriteResult render_and_write(const std::vector<Particle>& particles, const Grid& grid, const Scene& scene,
                             const std::string& path, bool write_float, const std::string& provenance);

// The whole command: builds the preset's file(s) from `out` (a file for
// spheres/zeolite, a prefix for zeolite-stages/extremes). Prints a summary.
int run_synth(Scene scene, const std::string& out, bool write_float);

}  // namespace tg::synth

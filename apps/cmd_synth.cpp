// `tomograin synth`: synthetic XCT specimens with exact ground truth
// (data_synth/scene.hpp has the presets and every scene key).
#include <memory>
#include <string>

#include "apps/command.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "data_synth/scene.hpp"

namespace cmd_synth {
struct Opts {
  std::string preset = "spheres", out, scene_file;
  int64_t seed = -1, size = 0;
  double voxel_um = 0;
  bool write_float = false;
};
}  // namespace cmd_synth

namespace cmd_synth {
static tg::app::Registrar reg{{"synth", 25,
      "Make a synthetic 16-bit XCT scan of a granular specimen whose every grain, fragment and pore is known.\n\n"
      "Writes an HDF5 file with /volume (u16 grey), /labels (u32 truth: the particle covering the largest\n"
      "part of each voxel, 0 where solid < 0.5), /truth (particle table) and, with --float, /reconstruction\n"
      "(f32 grey before rounding); and the truth table as PATH_truth.csv beside it. Partial volumes are\n"
      "exact (spheres: < 1e-10 per voxel; plane cuts: < 1e-4), then blur, noise, optional cupping/rings.\n"
      "Truth columns: id, kind, parent, cz_vox, cy_vox, cx_vox, radius_vox, volume_vox, Feret sizes, and\n"
      "mm twins; voxel (k,j,i) covers [k,k+1)x[j,j+1)x[i,i+1), so its centre is (k+0.5, j+0.5, i+0.5).\n\n"
      "Presets:\n"
      "  spheres         dense packing of D50 = 0.4 mm spheres (Cu 1.2) in a 3.2 mm box, 128^3 (25 um voxels)\n"
      "  zeolite         the reference study: D50 1.36 mm, Cu 1.07, Ø15 x 12.25 mm cylinder, pores;\n"
      "                  full field 1220 x 12.3 um; default 256^3 (coarser voxels)\n"
      "  zeolite-stages  one file per loading stage (strain 0, 4.4, 7.12, 11.28, 15.48 %; grains split into\n"
      "                  halves, wedges and chips): -o run.h5 writes run_stage0.h5 ... run_stage4.h5\n"
      "  extremes        -o x.h5 writes x_tiny, x_border, x_empty, x_solid, x_saturated (.h5, 64^3)\n\n"
      "Size: --size N alone keeps the field of view (coarser voxels); --voxel-um alone gives the full field\n"
      "at that voxel size; both crop the centre. Everything else (grey levels, noise, PSF, strains, breakage\n"
      "mix, container, sizes, an explicit particle list) goes in a --scene TOML file; see\n"
      "docs/data_synth.md for every key.\n\n"
      "Examples:\n"
      "  tomograin synth --preset spheres -o spheres.h5\n"
      "  tomograin synth --preset zeolite --size 512 -o zeolite512.h5\n"
      "  tomograin synth --preset zeolite --voxel-um 12.3 --size 400 -o crop.h5   # full resolution, crop\n"
      "  tomograin synth --preset zeolite-stages --seed 7 -o stages.h5\n"
      "  tomograin synth --preset zeolite --scene noisy.toml -o noisy.h5",
      [](CLI::App* sub) -> tg::app::Runner {
  auto o = std::make_shared<Opts>();
  sub->add_option("--preset", o->preset, "spheres | zeolite | zeolite-stages | extremes (default spheres)");
  sub->add_option("-o,--output", o->out, "Output .h5 file (a prefix for zeolite-stages and extremes)")->required();
  sub->add_option("--seed", o->seed, "Random seed (packing, pores, breakage, noise); default 1")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--voxel-um", o->voxel_um, "Voxel size in micrometres (default: field of view / size)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--size", o->size, "Cube edge in voxels (default: preset's; 1220 = zeolite full size)")
      ->check(CLI::Range(int64_t{1}, int64_t{4096}));
  sub->add_option("--scene", o->scene_file, "TOML scene file overriding the preset (strict keys)");
  sub->add_flag("--float", o->write_float, "Also write /reconstruction (f32 grey values)");
  return [o] {
    tg::synth::Scene scene = tg::synth::preset_scene(o->preset);
    if (!o->scene_file.empty()) {
      tg::Config cfg = tg::Config::from_file(o->scene_file);
      tg::synth::apply_config(scene, cfg);
    }
    if (o->seed >= 0) scene.seed = static_cast<uint64_t>(o->seed);
    if (o->voxel_um > 0) scene.voxel_um = o->voxel_um;
    if (o->size > 0) scene.size = o->size;
    return tg::synth::run_synth(std::move(scene), o->out, o->write_float);
  };
}}};
}  // namespace cmd_synth

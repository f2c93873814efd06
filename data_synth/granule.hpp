// Granule models: intact grains with intra-granular pores, and the fragments a
// grain breaks into (split halves, multi-fragments, chips), plus the loading-
// stage series built from one packing.
//
// Fragments are cut OUT of the parent sphere, never moved: every piece is the
// parent sphere ∩ half-spaces whose planes are offset by gap/2 from the
// fracture plane, so the fragments are separated by a void slab of width
// `gap` and stay inside the parent sphere, which keeps a non-overlapping
// packing non-overlapping.
//   split   two caps of height R − gap/2 (kind half; the half-sphere
//           when gap = 0: Dmax = 2R, Dmin = R, Dmed = 2R, FR = 0.5, AR = 2)
//   multi   3 or 4 wedges around a random axis through the centre (kind multi)
//   chip    a cap of thickness t ∈ [chip_min, chip_max]·R (kind chip) and the
//           body left below the gap (kind chipped)
// A pore stays in the fragment that contains it whole (with the gap), and is
// dropped where the fracture cuts it (it opens to the outside).
//
// Stage series: the packing is generated in the SHORTEST specimen (final
// strain); stage s stretches the centres' z about the bottom platen by
// (1 − ε_s)/(1 − ε_max) >= 1, which only increases centre distances, so no
// stage has overlaps; its solid fraction is the final one × (1 − ε_max)/(1 − ε_s).
// Which grains are broken at stage s: those whose draw u_g < broken[s], with
// u_g, the event and its geometry drawn once per grain from a counter-based
// stream keyed by the grain id: broken sets are nested across stages and a
// grain's fragments are identical (same ids, same planes) at every later stage,
// which is what tracking tests need. Fragment ids: first_fragment_id +
// 4 (grain id − 1) + piece (piece 0..3).
#pragma once
#include <cstdint>
#include <vector>

#include "data_synth/geometry.hpp"

namespace tg::synth {

enum class Event { none, split, multi, chip };

struct BreakageOptions {
  double gap = 1.5;                                     // void slab between fragments (voxels)
  double mix_split = 0.6, mix_multi = 0.25, mix_chip = 0.15;  // event mix (normalised)
  double chip_min = 0.15, chip_max = 0.35;              // chip thickness / R
  uint64_t seed = 1;
};

// Adds `count` non-overlapping pores of radius radius_frac·R at random places
// inside grain g (at least 0.05 R from its surface), seeded by (seed, g.id).
void add_pores(Particle& grain, int count, double radius_frac, uint64_t seed);

// The event drawn for grain `id`, given that it breaks.
Event draw_event(uint32_t id, const BreakageOptions& options);

// Fragments of an intact grain (one sphere, no planes) for event e.
std::vector<Particle> fragment(const Particle& grain, Event e, uint32_t first_fragment_id,
                               const BreakageOptions& options);

struct StageOptions {
  std::vector<double> strains{0.0, 0.044, 0.0712, 0.1128, 0.1548};  // axial strain per stage
  std::vector<double> broken{0.0, 0.15, 0.30, 0.50, 0.70};          // fraction of grains broken
  BreakageOptions breakage;
};

// Particles of stage `stage`: `grains` are the intact grains in the shortest
// specimen (voxel units), z_bottom the platen's z in voxels.
std::vector<Particle> stage_particles(const std::vector<Particle>& grains, double z_bottom, int stage,
                                      const StageOptions& options);

}  // namespace tg::synth

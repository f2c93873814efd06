// Loading-stage series that move like an oedometer test, with the truth
// lineage of every grain and fragment (issue #20: the tracker is tested on
// moving grains).
//
// The intact grains are packed in the SHORTEST specimen (final strain), as
// stage_particles() does (granule.hpp); at stage s, with strains e_s:
//  * uniform axial compression, bottom platen fixed, top platen moving down:
//    a grain centre's height above the bottom is scaled by
//    f_s = (1 - e_s)/(1 - e_max) (the specimen shortens by e_s - e_{s-1}
//    between stages; grains near the top travel most);
//  * per-grain jitter, a random walk whose steps grow with the strain
//    increment: x_s = sum_{q<=s} sqrt((e_q - e_{q-1})/e_max) jitter R N_q(g),
//    N_q(g) three standard normals (per axis), so its RMS at e_max is
//    jitter x R per axis;
//  * a rotation of every particle about its grain's centre, by
//    rotation_deg x e_s/e_max about an axis drawn once per grain (fragments
//    turn with it; intact spheres only turn their pores);
//  * primary breakage: grain g breaks at the first stage where its draw
//    u_g < broken[s] (nested across stages), into the pieces of fragment()
//    (split halves, 3-4 wedges, or a chipped body + chip);
//  * fragments drift apart: each piece moves out along its own side of the
//    fracture (minus the sum of its planes' normals) by
//    drift x R x (e_s - e_{b-1})/e_max after breaking at stage b;
//  * fragments break again: a half, wedge or chipped body still whole splits
//    at each later stage with probability `rebreak`, by a plane through its
//    parent sphere's centre that halves it exactly (containing a half's axis;
//    perpendicular to a wedge's edge), gap as for primary breakage; the two
//    pieces drift apart the same way. Chips never break again.
// The jitter, drift and rotation can make neighbours overlap by a fraction of
// a voxel (real grains touch too); the renderer gives each voxel to the
// particle covering most of it.
//
// Ids: grains keep theirs; pieces of grain g are first + 16 (g - 1) + p
// (p = 0..3), the two pieces of piece p are first + 16 (g - 1) + 4 + 2p + {0,1}.
// Truth events, per particle and stage (the tracker's vocabulary,
// track/track.hpp): intact (a continuation; stage 0 too), split (both halves
// of a split grain or fragment), fragmentation (every wedge), chipping (the
// chipped body), chip (the chip).
//
// Every draw is counter-based (seed, id, stage): same seed, same series.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/table.hpp"
#include "data_synth/granule.hpp"

namespace tg::synth {

struct MotionOptions {
  bool oedometer = false;    // false: stage_particles() (no jitter, rotation, drift or second breakage)
  double jitter = 0.04;      // RMS per-axis displacement at the final strain, x grain radius
  double rotation_deg = 5;   // rotation at the final strain, degrees
  double drift = 0.08;       // fragments' drift per unit of e/e_max, x grain radius
  double rebreak = 0.25;     // per-stage probability that a fragment splits again
};

// One particle of the series at one stage, with its truth lineage.
struct SeriesParticle {
  Particle particle;
  uint32_t parent = 0;   // id at the previous stage (0 at stage 0)
  uint32_t grain = 0;    // stage-0 ancestor
  std::string event;     // intact | split | fragmentation | chipping | chip
};

// Particles of stage `stage` (grains in the shortest specimen, voxel units;
// z_bottom the platen's z in voxels).
std::vector<SeriesParticle> oedometer_stage(const std::vector<Particle>& grains, double z_bottom, int stage,
                                            const StageOptions& stages, const MotionOptions& motion);

// The truth lineage in tracker columns (stage, label, parent_label, grain,
// event, volume_vox, cz_vox, cy_vox, cx_vox) from each stage's particles and
// its truth table (truth.hpp: rows of particles absent from the labels,
// label_voxels = 0, are dropped; a particle whose parent is absent at the
// previous stage is `new`, grain 0). volume_vox counts the label voxels.
Table lineage_truth(const std::vector<std::vector<SeriesParticle>>& stages, const std::vector<Table>& truth_tables);

}  // namespace tg::synth

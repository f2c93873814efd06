// The DEM's own lineage between the compared snapshots (issue 20): exact,
// because the DEM knows which sphere every fragment came from.
//
// Each DEM snapshot carries, per sphere, `previous_particle`: the particle id
// the sphere (or the sphere it was split from) had at the run's previous
// snapshot (dem/particles.hpp). Composing these maps over every snapshot of
// the run between two compared ones gives, for each particle of stage s, its
// particle at stage s-1 (its parent) and, carried down, its stage-0 grain.
//
// Events then come from the tracker's own classification
// (track::link_stage: intact / split / fragmentation / chipping with the same
// volume tolerances), on the particles' exact volumes (sum of their sphere
// volumes, in voxels of `voxel_m`), and events and summaries from
// track::derive_events / track::summarise: the DEM's events, % of intact
// grains broken and breakage by height fifth mean exactly what the
// experiment's tracked ones mean. Border cuts do not exist here (every
// particle is whole).
//
// Labels: particle p of stage s is written with label_of[s](p) (the truth
// labels of that stage's voxelised volume, so the tracker run on the imaged
// DEM path can be scored against this lineage with track::evaluate).
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/sphere_table.hpp"
#include "core/volume.hpp"
#include "track/track.hpp"

namespace tg::compare {

struct SnapshotLineage {
  SphereTable spheres;
  std::vector<int64_t> previous_particle;  // per sphere; empty when the snapshot has no such column
  std::string source;
};

// A DEM snapshot (.h5: the /spheres table of dem/snapshot.hpp; or a CSV
// sphere table) with its previous_particle column when present.
SnapshotLineage read_snapshot_lineage(const std::string& path);

// chain: every snapshot of the run, in order; stage_snapshot[s]: the index in
// `chain` of stage s (non-decreasing; equal = the same snapshot twice, every
// particle intact); label_of[s]: particle id -> label at stage s (particles
// missing from it get label id + 1). InputError naming the snapshot when a
// needed snapshot lacks previous_particle (a run written before the column
// existed), when the spheres of one particle disagree on it, or when it names
// a particle absent from the previous snapshot.
track::TrackResult dem_lineage(const std::vector<SnapshotLineage>& chain, const std::vector<size_t>& stage_snapshot,
                               const std::vector<std::map<int64_t, uint32_t>>& label_of, double voxel_m,
                               const track::TrackOptions& options = {});

// Each DEM snapshot is voxelised on its own grid (fitted to its spheres); the
// tracker needs one field of view, as a scanner gives: `v` copied into a grid
// of `shape` and geometry `g` (same voxel size), shifted by the whole-voxel
// offset between the origins; what falls outside is cut (as a scan's field
// of view cuts), new voxels are void. The sub-voxel rest of the offset is a
// rigid shift the tracker's registration absorbs.
Volume<uint32_t> on_grid(const Volume<uint32_t>& v, const Shape& shape, const Geometry& g);

}  // namespace tg::compare

// The truth table of a synthetic specimen: one row per particle, exact
// geometry (data_synth/geometry.hpp particle_truth) plus what the rendered
// label volume holds for it.
//
// Columns (voxel units follow core/shape.hpp: voxel (k,j,i) covers [k,k+1)…,
// centre at +0.5; *_mm = origin + voxel size × voxel coordinate):
//   id, kind (grain|half|multi|chip|chipped|cluster), parent,
//   cz_vox, cy_vox, cx_vox   exact centroid (pores removed)
//   radius_vox               radius of the parent sphere (largest sphere of a cluster)
//   volume_vox               exact volume, voxel³
//   dmax_vox, dmin_vox, dmed_vox, fr, ar   exact Feret metrics (NaN where no closed form)
//   pores                    number of intra-granular pores
//   label_voxels             voxels carrying this id in /labels
//   cropped                  1 when the particle reaches outside the volume
//   cz_mm, cy_mm, cx_mm, radius_mm, volume_mm3, dmax_mm, dmin_mm, dmed_mm
//                            (only when the geometry has a voxel size)
#pragma once
#include <vector>

#include "core/table.hpp"
#include "core/volume.hpp"
#include "data_synth/geometry.hpp"

namespace tg::synth {

// labels may be empty (label_voxels = 0 then). Truth of particles is computed in
// parallel; rows keep the order of `particles`.
Table truth_table(const std::vector<Particle>& particles, const Volume<uint32_t>& labels, Shape shape,
                  const Geometry& geometry);

}  // namespace tg::synth

// Partial-volume rendering of a list of particles into a solid-fraction volume
// and a truth label volume.
//
// solid(k,j,i)  = min(1, Σ_p coverage_p(voxel))   (coverage: data_synth/partial_volume.hpp;
//                 overlapping particles clip at 1)
// labels(k,j,i) = id of the particle covering the largest part of the voxel
//                 (ties: the earlier particle in the list), 0 where solid < 0.5.
//
// Method: the volume is cut into slabs of `slab` z-slices; OpenMP shares the
// slabs out with schedule(static, 1) and every slab is rendered by one thread
// from the particles whose bounding box meets it, in list order, so the sums
// are made in the same order whatever the thread count: the output is
// byte-identical for any number of threads. Only voxels in a particle's
// bounding box are visited; interior and exterior voxels are decided from
// corner distances, only surface voxels pay for the integral.
// Cost: O(Σ_p bbox_p voxels) + O(surface voxels · ~1 µs); memory: the two
// outputs (8 bytes/voxel) plus 4 bytes/voxel of one slab per thread.
//
// Coordinates are voxel units in the (z, y, x) convention of core/shape.hpp;
// `geometry` only labels the outputs with a voxel size and origin.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"
#include "data_synth/geometry.hpp"
#include "data_synth/partial_volume.hpp"

namespace tg::synth {

struct RenderOptions {
  int64_t slab = 8;         // z-slices per parallel work item
  int chord_order = 8;      // Gauss–Legendre order for plane-cut voxels (see partial_volume.hpp)
  int depth = 3;            // subdivision levels for plane-cut voxels (see partial_volume.hpp)
  bool labels = true;       // also build the label volume
  bool progress = false;    // progress bar on a terminal
};

struct Rendered {
  Volume<float> solid;      // solid fraction in [0, 1]
  Volume<uint32_t> labels;  // particle ids, 0 = void (empty when options.labels is false)
};

// Particles must have distinct ids > 0 (checked). Particles may lie partly or
// wholly outside the volume (cropped).
Rendered render(const std::vector<Particle>& particles, Shape shape, const Geometry& geometry = {},
                const RenderOptions& options = {});

// Mean of a solid-fraction volume, summed slice by slice in a fixed order
// (the same value for any thread count); 0 for an empty volume.
double mean_solid_fraction(const Volume<float>& solid);

}  // namespace tg::synth

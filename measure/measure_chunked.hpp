// measure_particles() for a label volume larger than memory: slab by slab
// along z, with the particle table of the whole volume (every number the
// same; tests/measure/measure_chunked_test.cpp compares them).
//
// Why slabs give the whole volume's numbers. Everything measured before the
// per-particle step is a sum of per-voxel terms, and each term looks only at
// the voxel's neighbours: its 6 face neighbours for the moments, boxes,
// border flags and boundary voxels (label_stats.hpp label_sums), its 26
// neighbours for the grey-level volume (grey_volume.hpp grey_volume_sums).
// A slab read with one slice more below and above its core (fewer at the
// volume's ends) sees every neighbour of its core's voxels, so each slab
// gives exact integer sums of its core, and the sums of the slabs add up to
// the whole volume's. Boundary voxels, appended per label slab after slab in
// z order, are the whole volume's lists in scan order, so the hull, the
// calipers and the oriented box (measure/particles.hpp
// particles_from_stats) see the same points in the same order.
//
// Not in slabs: the contact search (its normals read a ball of the volume
// around every contact; the caller leaves the coordination column out and
// says so) and surface areas (UsageError).
//
// Memory: one slab of labels (4 B/voxel) and, with a grey scan, of grey
// (2 B/voxel) at a time; the boundary voxels of every particle (16 B each;
// a granular packing has ~0.05-0.1 boundary voxels per voxel at grain radii
// of 20-40 voxels), kept until the end; per-label sums (~100 B a label).
// Cost: one read of the labels and of the grey scan (two of the grey scan
// when the caller takes its histogram first), O(V).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "core/volume.hpp"
#include "measure/particles.hpp"

namespace tg::measure {

// Bytes per voxel of measure_particles() on a whole volume held in memory
// (labels 4 B, grey scan 2 B, boundary lists and tables ~1 B: 6.73 B/voxel
// measured with the grey scan on a 1220^3 scan, bench/scale/RESULTS.md), and
// the boundary lists' share of a slab-by-slab run, per voxel of the volume.
inline constexpr double kMeasureBytesPerVoxel = 5.0;       // + 2 with a grey scan
inline constexpr double kMeasureListBytesPerVoxel = 1.5;   // boundary voxels x 16 B, with slack
inline constexpr int64_t kMeasureFixedBytes = int64_t(128) << 20;

struct MeasureChunkPlan {
  bool in_memory = true;       // fits under the limit: measure_particles() on the whole volume
  int64_t estimate_bytes = 0;  // the whole-volume estimate
  int64_t core = 0;            // core slices per slab
  int64_t slabs = 0;
  int64_t slab_bytes = 0;      // estimated peak of a slab run
};

// The plan for labels of shape s (with a grey scan when `grey`) under
// memory_limit_bytes (<= 0: no limit). UsageError when even one-slice slabs
// do not fit.
MeasureChunkPlan plan_measure_chunks(const Shape& s, bool grey, int64_t memory_limit_bytes);

// Slices [z0, z0 + nz) of the label volume / of the grey scan.
using LabelSlabSource = std::function<Volume<uint32_t>(int64_t z0, int64_t nz)>;
using GreySlabSource = std::function<Volume<uint16_t>(int64_t z0, int64_t nz)>;

// The particles of the whole volume (shape, geometry: the whole volume's),
// read in slabs of `core` slices (plus one slice of margin on each side).
// `grey` may be empty (no grey volumes; opt.grey is not read, opt.grey_levels
// is). opt.contacts is ignored (coordination stays -1); opt.surface is a
// UsageError. `progress` (may be empty) is called after each slab with the
// slices done.
std::vector<Particle> measure_particles_chunked(const Shape& shape, const Geometry& geometry,
                                                const LabelSlabSource& labels, const GreySlabSource& grey,
                                                int64_t core, const ParticleOptions& opt,
                                                const std::function<void(int64_t done, int64_t nz)>& progress = {});

}  // namespace tg::measure

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
// Contacts (the coordination column) in two passes (contacts.hpp
// ContactSearch): the crossings, integer sums, with the slabs above (their
// window reaches 4 slices below the core); then each contact's normal from
// the ball around its provisional point, in slabs with the ball's margin
// (~11 slices at the default 9-voxel radius), labels only. Surface areas
// are not available in slabs (UsageError).
//
// Memory: one slab of labels (4 B/voxel) and, with a grey scan, of grey
// (2 B/voxel) at a time; the boundary voxels of every particle, kept to the
// end, packed in 8 B each (three 16-bit indices: volumes of up to 65535
// voxels a side); per-label sums (~150 B a label). Boundary voxels are
// 0.10-0.15 per voxel of a granular scan at grain radii of 8-22 voxels
// (fragments add surface), ~0.04 at 55, so the lists take ~1 B/voxel of the
// whole volume. With a memory limit, each slab is as thick as the limit
// leaves room for beside the lists projected from the slices read so far
// (the table does not depend on the slab thickness).
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
// measured with the grey scan on a 1220^3 scan, bench/scale/RESULTS.md),
// the planned share of the boundary lists in a slab-by-slab run before any
// slab is read (per voxel of the volume: 0.15 boundary voxels x 8 B), and
// the process's own.
inline constexpr double kMeasureBytesPerVoxel = 5.0;  // + 2 with a grey scan held whole
inline constexpr double kMeasureListBytesPerVoxel = 1.2;
inline constexpr int64_t kMeasureFixedBytes = int64_t(128) << 20;

struct MeasureChunkPlan {
  bool in_memory = true;       // fits under the limit: measure_particles() on the whole volume
  int64_t estimate_bytes = 0;  // the whole-volume estimate
  int64_t core = 0;            // core slices of the first slab (later ones adapt)
  int64_t list_bytes = 0;      // the boundary lists' planned size
};

// How a whole-volume measure holds the grey scan: not at all, whole (2
// B/voxel), or slab by slab in one buffer of grey_window_slices() slices (a
// uint16 HDF5 scan, grey_volume.hpp), which the estimate counts as such.
enum class GreyHeld { none, whole, slabs };

// The plan for labels of shape s (with the grey scan held as `grey`) under
// memory_limit_bytes (<= 0: no limit). UsageError when even a one-slice
// slab does not fit beside the planned lists, or a side exceeds 65535.
MeasureChunkPlan plan_measure_chunks(const Shape& s, GreyHeld grey, int64_t memory_limit_bytes);

// Slices [z0, z0 + nz) of the label volume (the grey scan's: GreySlabSource,
// grey_volume.hpp).
using LabelSlabSource = std::function<Volume<uint32_t>(int64_t z0, int64_t nz)>;

struct ChunkedMeasureOptions {
  int64_t core = 0;                // > 0: every slab has this many core slices
  int64_t memory_limit_bytes = 0;  // core == 0: slabs as thick as this limit allows (header)
};

struct ChunkedMeasure {
  std::vector<Particle> particles;
  int64_t slabs = 0;
  int64_t boundary_voxels = 0;  // in the lists (8 B each)
  int64_t normal_slabs = 0;     // slabs of the contact normals' pass (opt.contacts)
  int64_t contacts = 0;
};

// The particles of the whole volume (shape, geometry: the whole volume's),
// read in slabs of core slices plus one slice of margin on each side (4
// below with contacts).
// `grey` may be empty (no grey volumes; opt.grey is not read, opt.grey_levels
// is). With opt.contacts the coordination column is filled (a second read of
// the labels); opt.surface is a UsageError, and so is a limit that leaves no
// room for a one-slice slab beside the lists. `progress` (may be empty) is called after each slab with
// the slices done.
ChunkedMeasure measure_particles_chunked(const Shape& shape, const Geometry& geometry, const LabelSlabSource& labels,
                                         const GreySlabSource& grey, const ChunkedMeasureOptions& chunks,
                                         const ParticleOptions& opt,
                                         const std::function<void(int64_t done, int64_t nz)>& progress = {});

}  // namespace tg::measure

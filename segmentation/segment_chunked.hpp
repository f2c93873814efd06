// segment() for a scan larger than memory: slab by slab along z, with labels
// identical (every voxel, same numbering) to segment() on the whole volume.
//
// Pass 1 (streaming, one or two reads of the scan): what is global and
// histogram-like, decided once for the whole scan: the field of view
// (FovScan: a per-row envelope carried from slab to slab), the histogram
// inside it, the level screen, the threshold and the bright level
// (segment.hpp GreyDecisions). A second read is needed only when a field of
// view is detected (the histogram is taken inside it, which is known only
// at the end of the first read).
//
// Pass 2: the cores, slabs of `core` slices (a multiple of 16) in z order,
// each read with a margin of M slices below and above (clipped at the
// scan's ends), run through segment()'s own chain (segment_slab) with the
// decisions of pass 1 and the whole scan's watershed quantisation.
//
// Why a margin makes the core exact. Every stage of the chain is local to a
// grain and its neighbours: the mask is per voxel; a pore or dim pocket is
// filled from its own component (one that touches the slab's face is left
// alone, and such a component lies within a pore's size of the face); the
// distance to the void is at most the largest inscribed radius, about R;
// an h-maximum's cap and a flood basin lie inside one grain (a cap of depth
// h cannot pass a neck more than h shallower than the peak); the flood's
// ties are broken by an order fixed per 8-slice block (watershed.hpp) and
// blocks start at multiples of 16 slices in the slab as in the scan (slab
// starts are multiples of 16); a merge looks at a label, its neighbours'
// volumes and their interfaces. So a particle with a voxel in the core is
// right when itself and its neighbours are whole in the slab and their
// voxels are farther than R from the slab's artificial faces: it spans at
// most a diameter 2R beyond the core, its neighbours another 2R, and their
// distances need R more. Rule: M = 5 R + 4 voxels (R the expected grain
// radius, SegmentOptions::grain_radius_vox; + 4 for grains a little larger
// than R), rounded up to a multiple of 16. ChunkedOptions::margin_vox
// overrides it (bench/segmentation/RESULTS.md measures smaller margins).
//
// Ownership and numbering. segment() numbers labels 1..count in raster
// order of each particle's first voxel (relabel_consecutive), leaving out
// those below min_size_vox. A slab's chain numbers its labels the same way
// without the size filter. A particle is owned by the slab whose core holds
// its first voxel; there it must not reach the slab's top face (it would
// be cut: the margin was too small for it) and it gets the next number of a
// running count over the slabs in z order (0 if smaller than
// min_size_vox), which is segment()'s number. A particle whose first voxel
// lies in the margin below the core was owned by an earlier slab: it is
// looked up by its first voxel's position and must have the voxel count it
// had there (else the two slabs disagree: error). A slab's core is written
// with these numbers.
//
// Checks that fail with UsageError (exit 2) naming the options: a particle
// cut by a slab face that reaches a core, a particle seen differently by two
// slabs, a memory limit too small for one slab of 16 core slices and its
// margins. ThresholdMethod::local is refused (its blocks need the volume).
//
// Memory: one slab at a time, ~8 B/voxel of the slab at peak (segment.hpp:
// 7 B/voxel with the split repair's grey code, + frontier), plus 4 B per
// particle for the numbering.
// Cost: pass 2 repeats the margins' work, (core + 2 M) / core of segment()'s
// time, plus one (two with a field of view) read of the scan in pass 1.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/volume.hpp"
#include "segmentation/segment.hpp"

namespace tg {

// Bytes per voxel of segment()'s peak, process included (6.03 measured at
// 1220^3 with the fixed-point distance map, segment.hpp; 1 more for the
// frontier and the allocator's slack), 1 more when the split repair keeps
// its grey code for after the watershed, and the process's own bytes: the
// estimate behind the choice between segment() and the slabs, and the
// slabs' thickness.
inline constexpr double kSegmentBytesPerVoxel = 7.0;
inline constexpr double kSplitGreyBytesPerVoxel = 1.0;
inline constexpr int64_t kSegmentFixedBytes = int64_t(128) << 20;

// The estimate for these options (the grey kept or not).
double segment_bytes_per_voxel(const SegmentOptions& o);

struct ChunkedOptions {
  int64_t memory_limit_bytes = 0;  // <= 0: no limit (segment() on the whole volume)
  int64_t margin_vox = -1;         // < 0: 5 R + 4 (header), rounded up to a multiple of 16
  double bytes_per_voxel = kSegmentBytesPerVoxel + kSplitGreyBytesPerVoxel;  // segment_bytes_per_voxel(options)
};

struct ChunkPlan {
  bool in_memory = true;       // the whole volume fits under the limit: segment() as usual
  int64_t estimate_bytes = 0;  // segment()'s estimated peak on the whole volume
  int64_t core = 0;            // core slices per slab (multiple of 16)
  int64_t margin = 0;          // margin slices below and above
  int64_t slabs = 0;
  int64_t slab_bytes = 0;      // estimated peak of the thickest slab
};

// The plan for a scan of shape s. UsageError when the limit is too small
// for one slab of 16 core slices with its margins.
ChunkPlan plan_chunks(const Shape& s, double grain_radius_vox, const ChunkedOptions& c);

// Reads slices [z0, z0 + nz) of the scan (u16, any geometry).
using GreySlabReader = std::function<Volume<uint16_t>(int64_t z0, int64_t nz)>;
// Stores slices [vz0, vz0 + nz) of `labels` as slices [z0, z0 + nz) of the output.
using LabelSlabWriter = std::function<void(int64_t z0, const Volume<uint32_t>& labels, int64_t vz0, int64_t nz)>;

struct ChunkedResult {
  SegmentResult result;  // decisions, count, dropped, solid fraction, seconds summed over slabs; no labels
  Shape shape;
  Geometry geometry;
  ChunkPlan plan;
  double pass1_seconds = 0, pass2_seconds = 0;
  int pass1_reads = 1;     // +1 when a field of view was detected, +1 when the grains were levelled (grain_levels.hpp)
  int restarts = 0;        // pass 2 restarted with coarser watershed levels (grains deeper than 254 / q)
  std::vector<std::pair<std::string, double>> slab_seconds;  // per slab: its z range, seconds
};

// Segments the scan slab by slab (plan.in_memory is ignored: always slabs).
// `geometry` is the scan's (its voxel size sets the distance map's spacing).
ChunkedResult segment_chunked(const Shape& shape, const Geometry& geometry, const GreySlabReader& read,
                              const LabelSlabWriter& write, const SegmentOptions& opt, const ChunkPlan& plan);

// The summary JSON of segment() (summary_json) with a "chunked" object
// (slabs, core, margin, seconds per pass, peak RSS and B/voxel); the counts
// that segment() takes over the whole volume but slabs cannot (pores,
// markers, merges, dim fraction) are null.
std::string summary_json(const ChunkedResult& r, const SegmentOptions& opt);

}  // namespace tg

// Connected-component labelling of a binary volume (6, 18 or 26
// connectivity), with consecutive labels and a size filter.
//
// Method: two passes with union-find (Rosenfeld and Pfaltz 1966,
// "Sequential operations in digital picture processing", J. ACM 13:471-494,
// doi:10.1145/321356.321357) over runs of foreground voxels along x rather
// than single voxels (as in He, Chao and Suzuki 2008, "A run-based two-scan
// labeling algorithm", IEEE TIP 17:749-756, doi:10.1109/TIP.2008.919369).
// Each run gets an id in raster order; each run is united with the runs it
// touches in its backward rows (2 rows for 6-connectivity, 4 for 18 and
// 26); the union keeps the smaller id as root, so every root is the first
// run of its component in raster order. Slabs of slices are united in
// parallel (no two slabs share a run), then the seams between them. Final
// labels are 1..count, numbered in raster order of each component's first
// voxel, whatever the thread count; 0 is background.
//
// Cost: O(N alpha(R)) time, every pass parallel but the numbering of the R
// runs; memory is the u32 label volume (4 B/voxel) plus 4 B per run.
// Throws ResourceError if there are more than 2^32 - 2 runs.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg {

// Which voxels of the mask are the foreground to label.
enum class Phase { nonzero, zero };

struct ComponentsOptions {
  int connectivity = 26;         // 6 (faces), 18 (+edges) or 26 (+corners)
  Phase phase = Phase::nonzero;  // label the nonzero voxels (solid) or the zero ones (void)
  int64_t min_size = 1;          // components with fewer voxels are set to 0 (not counted)
};

struct ComponentsResult {
  uint32_t count = 0;          // labels 1..count
  int64_t dropped = 0;         // components removed by min_size
  std::vector<int64_t> sizes;  // sizes[l] = voxels of label l (sizes[0] unused, 0)
};

// Labels `mask` into `labels` (reallocated if its shape differs; geometry copied).
ComponentsResult connected_components(const Volume<uint8_t>& mask, Volume<uint32_t>& labels,
                                      const ComponentsOptions& opt = {});

struct RelabelResult {
  uint32_t count = 0;          // labels 1..count after renumbering
  int64_t dropped = 0;         // labels removed by min_size
  std::vector<int64_t> sizes;  // sizes[l] = voxels of new label l
};

// Renumbers arbitrary labels to 1..count in raster order of first
// appearance, setting labels with fewer than min_size voxels to 0. O(N),
// in parallel (each thread lists the labels of its share in order).
// With a premap, each label l is first read as premap[l] (every label must
// be below premap.size()): a merge's roots applied in the same pass.
// exempt (or nullptr): exempt[l] != 0 keeps label l (after the premap)
// whatever its size.
RelabelResult relabel_consecutive(Volume<uint32_t>& labels, int64_t min_size = 1,
                                  const std::vector<uint32_t>* premap = nullptr,
                                  const std::vector<uint8_t>* exempt = nullptr);

}  // namespace tg

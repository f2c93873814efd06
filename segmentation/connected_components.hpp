// Connected-component labelling of a binary volume (6, 18 or 26
// connectivity), with consecutive labels and a size filter.
//
// Method: the classic two-pass algorithm with union-find (Rosenfeld and
// Pfaltz 1966, "Sequential operations in digital picture processing",
// J. ACM 13:471-494, doi:10.1145/321356.321357; union-find as in Wu, Otoo
// and Suzuki 2009, doi:10.1007/s10044-008-0109-y). Pass 1 scans in raster
// order, gives each foreground voxel the provisional label of an already
// visited neighbour (the backward half of the neighbourhood: 3, 9 or 13
// voxels) or a new one, and unites the labels it sees. The union keeps the
// smaller label as root, so every root is the first label of its component
// in raster order. Pass 2 replaces each label by its component's final
// number. Final labels are 1..count, numbered in raster order of each
// component's first voxel (independent of any thread count: the passes are
// serial), 0 is background.
//
// Cost: O(N alpha(N)) time; memory is the u32 label volume (4 B/voxel) plus
// 4 B per provisional label. Throws ResourceError if more than 2^32 - 2
// provisional labels would be needed.
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
// appearance, setting labels with fewer than min_size voxels to 0. O(N).
RelabelResult relabel_consecutive(Volume<uint32_t>& labels, int64_t min_size = 1);

}  // namespace tg

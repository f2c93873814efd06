// Runs of foreground voxels along x: the first step of the run-based
// labellings (connected_components, pore_filter), which work on runs
// (a few per row of a granular scan) instead of single voxels.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg::seg {

// first[r] = the number of runs of foreground voxels (fg(value) true) in
// the rows before row r (rows in raster order, r = k ny + j); the last
// entry, first[nz ny], counts them all. Rows are counted in parallel.
template <class IsFg>
std::vector<int64_t> run_offsets(const Volume<uint8_t>& mask, IsFg fg) {
  const Shape s = mask.shape();
  const int64_t nx = s.nx, rows = s.nz * s.ny;
  const uint8_t* m = mask.data();
  std::vector<int64_t> first(size_t(rows) + 1, 0);
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    const uint8_t* row = m + r * nx;
    // A run starts where a voxel is foreground and the one before it is
    // not: each voxel against its neighbour, with no state carried from
    // one voxel to the next, so the compiler vectorises the loop.
    int64_t c = nx > 0 && fg(row[0]);
    for (int64_t i = 1; i < nx; ++i) c += int64_t(fg(row[i]) & !fg(row[i - 1]));
    first[size_t(r) + 1] = c;
  }
  for (int64_t r = 0; r < rows; ++r) first[size_t(r) + 1] += first[size_t(r)];
  return first;
}

}  // namespace tg::seg

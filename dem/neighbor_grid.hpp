// Verlet neighbour list by cell binning with a counting sort (the grid of
// taichi_dem's dem.py), plus the O(n²) brute-force list kept as its oracle.
//
// A pair (i, j), i < j, is listed when |x_i - x_j| < r_i + r_j + skin. With a
// skin the list stays valid until some sphere has moved more than skin/2
// since the build (two spheres approaching each other close at most twice
// that), so it is rebuilt only then (Engine checks the displacement).
//
// Method: cubic cells of side h >= 2 r_max + skin over the spheres' bounding
// box, so every listed pair lies in the same or adjacent cells (invariant
// asserted). Counting sort: count spheres per cell, prefix sum, scatter ids
// into one array (cell_start/cell_ids). Then each sphere i scans the 27
// cells around its own and keeps j > i within range; the per-i lists are
// sorted by j so the result (CSR: offsets + j) does not depend on the cell
// traversal order or on the number of threads.
// Cost: O(n + pairs) time, O(n + cells) memory; the cell count is capped at
// about 8n (cells grow when spheres are far apart) so memory stays O(n).
#pragma once
#include <cstdint>
#include <vector>

#include "dem/particles.hpp"

namespace tg::dem {

struct PairListCSR {
  std::vector<int64_t> offsets;  // size n+1: pairs of i are [offsets[i], offsets[i+1])
  std::vector<int64_t> j;        // partner, ascending within each i, j > i
  int64_t pairs() const { return static_cast<int64_t>(j.size()); }
};

// Cell-list build; skin >= 0 (m). Uses OpenMP; output independent of threads.
PairListCSR build_pairs_grid(const Particles& p, double skin);
// O(n²) reference with the same output convention.
PairListCSR build_pairs_brute_force(const Particles& p, double skin);

}  // namespace tg::dem

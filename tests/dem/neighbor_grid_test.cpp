// The cell-list pair list must equal the O(n²) oracle exactly.
#include "dem/neighbor_grid.hpp"

#include <gtest/gtest.h>

#include <random>

namespace tg::dem {
namespace {

Particles random_spheres(int n, double box, double rmin, double rmax, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, box), ur(rmin, rmax);
  Particles p;
  for (int i = 0; i < n; ++i) p.append_sphere(u(rng), u(rng), u(rng), ur(rng), 2180, i);
  return p;
}

TEST(NeighborGrid, MatchesBruteForce) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Particles p = random_spheres(1500, 0.02, 0.4e-3, 0.8e-3, seed);
    for (double skin : {0.0, 2e-4, 1e-3}) {
      const PairListCSR g = build_pairs_grid(p, skin), b = build_pairs_brute_force(p, skin);
      EXPECT_GT(b.pairs(), 0);
      EXPECT_EQ(g.offsets, b.offsets);
      EXPECT_EQ(g.j, b.j);
    }
  }
}

TEST(NeighborGrid, FarFlungSpheresKeepGridSmall) {
  // Two clusters 1 km apart: the cell size must grow instead of allocating 1e18 cells.
  Particles p = random_spheres(200, 0.01, 0.5e-3, 0.6e-3, 7);
  p.append_sphere(1000, 1000, 1000, 0.5e-3, 2180, 999);
  p.append_sphere(1000, 1000, 1000.0009, 0.5e-3, 2180, 1000);
  const PairListCSR g = build_pairs_grid(p, 1e-4), b = build_pairs_brute_force(p, 1e-4);
  EXPECT_EQ(g.j, b.j);
  EXPECT_EQ(g.offsets, b.offsets);
}

TEST(NeighborGrid, EmptyAndSingle) {
  Particles p;
  EXPECT_EQ(build_pairs_grid(p, 1e-4).pairs(), 0);
  p.append_sphere(0, 0, 0, 1e-3, 2180, 0);
  EXPECT_EQ(build_pairs_grid(p, 1e-4).pairs(), 0);
}

}  // namespace
}  // namespace tg::dem

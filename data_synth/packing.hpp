// Dense random packing of spheres with a size distribution, in a box or a
// vertical cylinder, without overlaps.
//
// Method: collective rearrangement with growth (Jodrey & Tory 1985,
// doi:10.1103/PhysRevA.32.2347; the growth schedule is that of
// Lubachevsky & Stillinger 1990, doi:10.1007/BF01025983, with overlap
// relaxation in place of event-driven dynamics).
//  1. Diameters are drawn from a log-normal law by number (median D50, σ from
//     Cu = D60/D10: σ = ln Cu / (z₆₀ − z₁₀), z the standard normal quantiles),
//     truncated to ±3σ, until their volume reaches target_fraction × container.
//  2. Centres are placed uniformly at random; all radii are scaled by s = 0.7.
//  3. Gauss–Seidel sweeps push every overlapping pair apart symmetrically
//     along the centre line and push spheres back inside the walls, with a
//     counting-sort cell grid for neighbours, until the largest overlap is
//     below `tolerance` × radius; then s grows by 1 % (finally to exactly 1).
//     If a stage does not converge within `stage_sweeps` sweeps the packing is
//     jammed: the sphere with the largest summed overlap is removed (so the
//     drawn sizes stay exact and the fraction drops by one grain) and the
//     stage retried.
//  4. At s = 1, sweeps continue to 1e-7 relative overlap, then all radii are
//     multiplied by min(1, min over pairs d/(ri+rj), wall margins) so that there
//     is provably no overlap (the factor, ~1 − 1e-7, is reported).
// Deterministic: one thread, fixed order, counter-based random numbers.
// Cost: O(N) per sweep; a few thousand sweeps for ~1000 spheres (< 1 s).
// Achieved (tests/data_synth/packing_test.cpp, zeolite bench): ~0.58–0.60
// overall in a Ø/D50 ≈ 11 cylinder, higher in the interior (walls loosen
// the first layer); random sequential addition alone would stall near 0.38.
//
// Coordinates: any length unit (the scene uses mm), DEM convention: cylinder
// axis along z through x = y = 0, bottom at z = 0; a box spans
// [0, Lz] × [−Ly/2, Ly/2] × [−Lx/2, Lx/2].
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "data_synth/geometry.hpp"

namespace tg::synth {

enum class Container { box, cylinder };

struct PackingOptions {
  Container container = Container::cylinder;
  double diameter = 15.0;            // cylinder diameter
  double height = 12.25;             // cylinder or box height (z)
  double box_y = 10.0, box_x = 10.0; // box sides
  double d50 = 1.36;                 // median diameter (by number)
  double cu = 1.07;                  // uniformity coefficient D60/D10 (1 = monodisperse)
  double target_fraction = 0.60;     // volume drawn = target × container volume (before jamming removals)
  double tolerance = 1e-3;           // relative overlap accepted during growth
  int stage_sweeps = 200;            // sweeps per growth stage before declaring a jam
  uint64_t seed = 1;
};

struct Packing {
  std::vector<Sphere> spheres;   // (z, y, x) centres, radii; same unit as the options
  double fraction = 0;           // solid volume / container volume
  double interior_fraction = 0;  // in the interior box (one D50 from every wall)
  double final_scale = 1;        // factor applied to the radii for zero overlap
  int sweeps = 0, removed = 0;   // relaxation sweeps, grains removed at jams
  double mean_contacts = 0;      // neighbours closer than 1e-3 D50 per sphere
  double min_gap = 0;            // smallest surface gap between two spheres (>= 0)
};

Packing dense_packing(const PackingOptions& options);

// σ of ln D for a log-normal law with uniformity coefficient cu = D60/D10.
double lognormal_sigma(double cu);

// Solid fraction of spheres inside the box [lo, hi] (exact partial volumes),
// and the largest pair overlap (ri + rj − d, <= 0 when none). Brute force O(N²)
// overlap check: the test oracle for the cell grid.
double fraction_in_box(const std::vector<Sphere>& spheres, const Vec3& lo, const Vec3& hi);
double max_overlap(const std::vector<Sphere>& spheres);

}  // namespace tg::synth

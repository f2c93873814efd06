// Grains of different brightness: each grain's grey brought to the solid's
// level before the threshold, so that one global threshold cuts every grain
// at half its own contrast over the void.
//
// Why. A global threshold sits near half the solid's contrast. A grain much
// darker than the rest (another mineral, a porous grain; blind_scene.py
// --grain-contrast 0.35,1) lies partly or wholly under it: its voxels above
// it are noise-lifted specks, its volume shrinks or it is lost (F1 0.68
// against 0.99 on grains of one brightness). No global level fixes that:
// void + 5 raw noise sigmas is already above the dimmest grains at CNR 13.
//
// Method: local contrast normalisation (the flat-field idea applied grain by
// grain; cf. Pizer et al. 1987, "Adaptive histogram equalization and its
// variations", CVGIP 39:355, for contrast taken from a neighbourhood). With
// V the void's grey peak, P the brightest grains' level (the 99th
// percentile of the smoothed solid) and s the smoothed void noise sigma
// (all from the histograms segment() already takes):
//   S = the grey smoothed by a Gaussian of 1 voxel (noise / ~6 at white noise);
//   M = the largest S within a cube of half-width `reach_vox` (a grain's own
//       level reaches its rim and the partial volume around it);
//   gain = (P - V) / (M - V), clamped to [1, max_gain]; 1 where M - V is
//       under min_excess_sigmas s (void: nothing there to brighten);
//   w = clamp((gain - 1) / (smooth_from_gain - 1), 0, 1);
//   grey' = V + gain ((1 - w) (grey - V) + w (S - V)).
// A grain at the solid's level is left as it is (gain 1: M >= P); a dim
// grain is raised to P, read from the smoothed grey where the gain would
// otherwise raise the raw noise with it (a grain at 0.35 of the contrast
// has a raw CNR of 4.5: per voxel it cannot be told from the void).
//
// When it runs (segment.hpp SegmentOptions::grain_levels; whole volumes and
// slab by slab, each slab levelled from grain_levels_reach() slices beyond
// its own): where the grains differ in brightness, by either of two signs
// read from the split repair's smoothed sample histograms:
//  * the grains' levels spread: the smoothed solid peak is at least
//    min_spread_ratio times as wide as the grey varies inside one grain
//    (the split repair's within-grain sigma, split_labels.hpp). Grains of one
//    brightness measure 0.8-1.3, cupping and textured grains 1.2-2.2, grain
//    contrast 0.85-1 2.1-3.8, 0.7-1 3.4-8.3, 0.5-1 11, 0.35-1 14-20 (blind
//    scenes, R 8-20);
//  * a population of darker grains (another mineral): a peak of its own
//    between the void and the solid (dim_population, below), which leaves
//    the solid peak as narrow as one brightness does.
// Elsewhere it would only raise partial-volume crumbs at the faces and
// small blurred chips (their smoothed peak is below P), which grow by it:
// on grains of one brightness at R 20 it cost F1 0.006.
//
// Measured (bench/segmentation/RESULTS.md "Grains of different brightness:
// each grain's own level"), on scans made after the rules were fixed: grain
// contrast 0.35-1 and 0.5-1, F1 0.58-0.85 -> 0.95-0.99; two minerals (10-30
// % of the grains at 0.4-0.5), 0.26-0.73 -> 0.96-1.00; the sweep's rows it
// runs on up, the others untouched.
//
// Cost: three separable passes of the Gaussian and three of the maximum,
// O(N) time, OpenMP over slices (results independent of the thread count);
// two 16-bit volumes besides the scan (S, then M, which becomes grey').
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"

namespace tg {

struct GrainLevelsOptions {
  double smoothing_sigma_vox = 1.0;  // S's Gaussian
  int reach_vox = 3;                 // M's cube half-width
  double max_gain = 1.0 / 0.3;       // grains down to 0.3 of the contrast are raised
  double smooth_from_gain = 1.0 / 0.6;  // from this gain on, grey' is read from S alone
  double min_excess_sigmas = 8.0;    // M - V below this many smoothed void sigmas: left alone
  double min_spread_ratio = 2.0;     // segment(): runs where the solid peak / within-grain sigma >= this
};

// The levels the normalisation reads, in grey levels.
struct GrainLevelsInput {
  double void_level = 0;      // V
  double solid_level = 0;     // P (the brightest grains' level)
  double smoothed_sigma = 0;  // s (the smoothed void's noise sigma)
};

// A population of grains darker than the rest (two minerals, say): a peak
// of the smoothed grey's histogram between the void and the brightest
// grains, which grains of one brightness do not have (there the partial
// volume between the phases falls from the void and rises to the solid: no
// interior maximum). The histogram in bins of 1/40 of (P - V), averaged
// over 3 bins; searched between V + max(4 s, 0.15 (P - V)) and
// P - max(4 s, 0.1 (P - V)); found where its fullest bin there is an
// interior maximum at least min_prominence times the emptiest bin on either
// side of it (between it and the void, and between it and P). Measured on
// blind scenes (R 20, whole volumes): grains of one brightness have no
// interior maximum; cupping 0.3 one of prominence 1.2; 5 % of the grains at
// 0.45 of the contrast 2.1-2.6; 20 % 3.5-5.
struct DimPopulation {
  bool found = false;
  double level = 0;       // its peak's grey
  double prominence = 0;  // its peak over the deeper of the two floors beside it (0: no interior maximum)
};
inline constexpr double kDimPopulationProminence = 1.35;
// in.solid_level: the smoothed solid's mode (segment.cpp).
DimPopulation dim_population(const std::vector<int64_t>& smoothed_hist, const GrainLevelsInput& in,
                             double min_prominence = kDimPopulationProminence);

struct GrainLevelsResult {
  bool used = false;
  double spread_ratio = 0;       // the smoothed solid peak's sigma / the within-grain sigma
  DimPopulation dim;             // a population of darker grains (dim_population)
  GrainLevelsInput levels;
  int64_t voxels_raised = 0;     // voxels with gain > 1
  int64_t voxels_from_smoothed = 0;  // voxels with w = 1
};

// grey' as in the header; geometry kept. result's counts are over slices
// [count_z0, count_z1) (count_z1 < 0: to the last; a slab's core). Throws
// UsageError on levels that do not order V < P or a smoothed sigma <= 0.
Volume<uint16_t> normalise_grain_levels(const Volume<uint16_t>& grey, const GrainLevelsInput& in,
                                        const GrainLevelsOptions& opt, GrainLevelsResult* result = nullptr,
                                        int64_t count_z0 = 0, int64_t count_z1 = -1);

// A grey value depends on the grey within this many slices (the smoothing's
// and the maximum's half-widths, default options): a slab levelled from
// this many more slices either side is exact.
int64_t grain_levels_reach(const GrainLevelsOptions& opt);

}  // namespace tg

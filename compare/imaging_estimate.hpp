// Estimating the imaging model's grey levels and noise from an experimental
// scan's histogram, so a voxelised DEM packing looks like that scan
// (`tomograin voxelise --like SCAN`).
//
// Method (a two-peak histogram: void and solid):
//   1. Otsu's threshold splits the 16-bit histogram into a dark and a bright
//      class (segmentation/threshold.hpp).
//   2. The histogram is rebinned to `bin` grey levels and smoothed by a
//      Gaussian of `smooth_bins` bins; each class's highest bin marks its peak.
//   3. Each peak is read on its OUTER side only (below the void peak, above
//      the solid peak), where partial-volume voxels at grain surfaces do not
//      reach: a Gaussian N(mu, sigma) falls to half its height at
//      mu -+ 1.1774 sigma and to a tenth at mu -+ 2.1460 sigma, so the two
//      crossings give sigma (smoothing variance removed) and mu: void_grey,
//      solid_grey. The flat top's argmax is not used as the level (it wanders
//      by ~0.2 sigma with the counting noise).
//      noise_sigma is the taller peak's sigma (more voxels far from a surface).
//   Measured on a zeolite-stages scan (128³, grains ≈ 12 voxels; truth void
//   9000 / solid 38000 / sigma 900): see tests/compare/imaging_estimate_test.cpp
//   and docs/compare.md.
// Not estimated: the PSF (blur) width, which the histogram of a scan whose
// voxels are mostly deep inside void or solid does not constrain; it keeps
// its default (data_synth/imaging.hpp). The imaging model adds noise after the
// blur, so the outer peak width is the model's noise_sigma directly.
// Cost: O(N) for the histogram + O(65536).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/volume.hpp"
#include "data_synth/imaging.hpp"

namespace tg::compare {

struct GreyEstimateOptions {
  int bin = 16;              // grey levels per histogram bin
  double smooth_bins = 2.0;  // Gaussian smoothing σ, bins
};

struct GreyEstimate {
  double void_grey = 0, solid_grey = 0, noise_sigma = 0;
  double sigma_void = 0, sigma_solid = 0;  // per-peak estimates; noise_sigma = the taller peak's
  int threshold = 0;                       // Otsu split
  std::string method = "otsu split; Gaussian fit to the outer half/tenth-maximum crossings of each peak; noise from the taller peak";
};

// hist: 65536 counts (segmentation's histogram_u16). InputError when a class is empty.
GreyEstimate estimate_grey_levels(const std::vector<int64_t>& hist, const GreyEstimateOptions& opt = {});
GreyEstimate estimate_grey_levels(const Volume<uint16_t>& scan, const GreyEstimateOptions& opt = {});

// `base` with void_grey, solid_grey and noise_sigma replaced by the estimate.
synth::ImagingOptions imaging_like(const GreyEstimate& e, synth::ImagingOptions base = {});

}  // namespace tg::compare

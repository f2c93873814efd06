// Estimating the imaging model's grey levels and noise from an experimental
// scan's histogram, so a voxelised DEM packing looks like that scan
// (`tomograin voxelise --like SCAN`).
//
// Method (a two-peak histogram: void and solid):
//   1. Otsu's threshold splits the 16-bit histogram into a dark and a bright
//      class (segmentation/threshold.hpp).
//   2. The histogram is rebinned to `bin` grey levels and smoothed by a
//      Gaussian of `smooth_bins` bins; each class's peak (mode) is its grey
//      level: void_grey = dark mode, solid_grey = bright mode.
//   3. Noise σ from the half width at half maximum of each peak on its OUTER
//      side (below the void peak, above the solid peak), where partial-volume
//      voxels at grain surfaces do not widen it: σ = HWHM / √(2 ln 2), with
//      the smoothing kernel's variance removed; the two peaks' σ are averaged.
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
  double sigma_void = 0, sigma_solid = 0;  // per-peak estimates, averaged into noise_sigma
  int threshold = 0;                       // Otsu split
  std::string method = "otsu split; class modes; outer-side HWHM";
};

// hist: 65536 counts (segmentation's histogram_u16). InputError when a class is empty.
GreyEstimate estimate_grey_levels(const std::vector<int64_t>& hist, const GreyEstimateOptions& opt = {});
GreyEstimate estimate_grey_levels(const Volume<uint16_t>& scan, const GreyEstimateOptions& opt = {});

// `base` with void_grey, solid_grey and noise_sigma replaced by the estimate.
synth::ImagingOptions imaging_like(const GreyEstimate& e, synth::ImagingOptions base = {});

}  // namespace tg::compare

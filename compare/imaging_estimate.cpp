#include "compare/imaging_estimate.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "segmentation/threshold.hpp"

namespace tg::compare {
namespace {

// Outer half width at half maximum of the peak at bin `mode`, walking with
// `step` (-1 down, +1 up), linearly interpolated between bins; in bins.
double outer_hwhm(const std::vector<double>& h, int64_t mode, int step) {
  const double half = 0.5 * h[static_cast<size_t>(mode)];
  int64_t b = mode;
  while (b + step >= 0 && b + step < static_cast<int64_t>(h.size()) && h[static_cast<size_t>(b + step)] > half) b += step;
  const int64_t nb = b + step;
  if (nb < 0 || nb >= static_cast<int64_t>(h.size())) return static_cast<double>(std::abs(b - mode));
  const double hb = h[static_cast<size_t>(b)], hn = h[static_cast<size_t>(nb)];
  const double t = hb > hn ? (hb - half) / (hb - hn) : 0.0;
  return static_cast<double>(std::abs(b - mode)) + t;
}

}  // namespace

GreyEstimate estimate_grey_levels(const std::vector<int64_t>& hist, const GreyEstimateOptions& opt) {
  if (hist.size() != 65536) throw UsageError("estimate_grey_levels: expected a 65536-bin histogram");
  if (opt.bin < 1 || !(opt.smooth_bins >= 0)) throw UsageError("estimate_grey_levels: bin >= 1, smooth_bins >= 0");
  GreyEstimate e;
  e.threshold = otsu_threshold(hist).value;
  // Rebin, then smooth with a truncated (4σ) Gaussian.
  const int64_t nb = (65536 + opt.bin - 1) / opt.bin;
  std::vector<double> coarse(static_cast<size_t>(nb), 0.0), h(static_cast<size_t>(nb), 0.0);
  for (size_t g = 0; g < hist.size(); ++g) coarse[g / static_cast<size_t>(opt.bin)] += static_cast<double>(hist[g]);
  const int64_t rad = static_cast<int64_t>(std::ceil(4 * opt.smooth_bins));
  std::vector<double> kern(static_cast<size_t>(2 * rad + 1), 1.0);
  if (opt.smooth_bins > 0)
    for (int64_t d = -rad; d <= rad; ++d)
      kern[static_cast<size_t>(d + rad)] = std::exp(-0.5 * d * d / (opt.smooth_bins * opt.smooth_bins));
  for (int64_t b = 0; b < nb; ++b) {
    double acc = 0;
    for (int64_t d = -rad; d <= rad; ++d) {
      const int64_t q = std::clamp<int64_t>(b + d, 0, nb - 1);
      acc += kern[static_cast<size_t>(d + rad)] * coarse[static_cast<size_t>(q)];
    }
    h[static_cast<size_t>(b)] = acc;
  }
  const int64_t split = e.threshold / opt.bin;  // bins <= split: dark class
  if (split < 0 || split + 1 >= nb) throw InputError("grey-level estimate: the histogram has no second class");
  const auto dark = std::max_element(h.begin(), h.begin() + split + 1);
  const auto bright = std::max_element(h.begin() + split + 1, h.end());
  if (!(*dark > 0) || !(*bright > 0)) throw InputError("grey-level estimate: one class of the histogram is empty");
  const int64_t md = dark - h.begin(), mb = bright - h.begin();
  // Bin centres in grey levels.
  e.void_grey = (static_cast<double>(md) + 0.5) * opt.bin - 0.5;
  e.solid_grey = (static_cast<double>(mb) + 0.5) * opt.bin - 0.5;
  // σ of the measured peak = HWHM / sqrt(2 ln 2); remove the smoothing (σ_s bins)
  // and rebinning (width² / 12) variances, which add to the noise variance.
  const double k = 1.0 / std::sqrt(2.0 * std::log(2.0));
  const double extra = opt.smooth_bins * opt.smooth_bins + 1.0 / 12.0;
  auto sigma = [&](double hwhm_bins) {
    const double s2 = hwhm_bins * hwhm_bins * k * k - extra;
    return s2 > 0 ? std::sqrt(s2) * opt.bin : 0.0;
  };
  e.sigma_void = sigma(outer_hwhm(h, md, -1));
  e.sigma_solid = sigma(outer_hwhm(h, mb, +1));
  e.noise_sigma = 0.5 * (e.sigma_void + e.sigma_solid);
  return e;
}

GreyEstimate estimate_grey_levels(const Volume<uint16_t>& scan, const GreyEstimateOptions& opt) {
  return estimate_grey_levels(histogram_u16(scan), opt);
}

synth::ImagingOptions imaging_like(const GreyEstimate& e, synth::ImagingOptions base) {
  base.void_grey = e.void_grey;
  base.solid_grey = e.solid_grey;
  base.noise_sigma = e.noise_sigma;
  return base;
}

}  // namespace tg::compare

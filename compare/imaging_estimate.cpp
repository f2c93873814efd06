#include "compare/imaging_estimate.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "segmentation/threshold.hpp"

namespace tg::compare {
namespace {

// Distance (bins, linearly interpolated) from the peak at `mode` to where the
// histogram first falls to `frac` of the peak height, walking with `step`
// (-1 down, +1 up).
double outer_crossing(const std::vector<double>& h, int64_t mode, int step, double frac) {
  const double level = frac * h[static_cast<size_t>(mode)];
  int64_t b = mode;
  while (b + step >= 0 && b + step < static_cast<int64_t>(h.size()) && h[static_cast<size_t>(b + step)] > level) b += step;
  const int64_t nb = b + step;
  if (nb < 0 || nb >= static_cast<int64_t>(h.size())) return static_cast<double>(std::abs(b - mode));
  const double hb = h[static_cast<size_t>(b)], hn = h[static_cast<size_t>(nb)];
  const double t = hb > hn ? (hb - level) / (hb - hn) : 0.0;
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
  // A Gaussian peak N(mu, sigma) falls to a fraction f of its height at
  // mu -+ sigma sqrt(-2 ln f): two crossings on the outer side (f = 1/2, 1/10)
  // give sigma and mu without using the flat, noisy top (whose argmax wanders
  // by ~0.2 sigma) or the inner side (partial-volume voxels).
  const double z05 = std::sqrt(2 * std::log(2.0)), z01 = std::sqrt(2 * std::log(10.0));
  const double extra = opt.smooth_bins * opt.smooth_bins + 1.0 / 12.0;  // smoothing + rebinning variance
  auto fit = [&](int64_t mode, int step, double& mu, double& sigma) {
    const double d05 = outer_crossing(h, mode, step, 0.5), d01 = outer_crossing(h, mode, step, 0.1);
    const double sm = (d01 - d05) / (z01 - z05);
    const double s2 = sm * sm - extra;
    const double sb = s2 > 0 ? std::sqrt(s2) : 0.0;
    const double pos = static_cast<double>(mode) + step * d05 - step * z05 * sm;  // bins
    mu = (pos + 0.5) * opt.bin - 0.5;
    sigma = sb * opt.bin;
  };
  fit(md, -1, e.void_grey, e.sigma_void);
  fit(mb, +1, e.solid_grey, e.sigma_solid);
  // The taller peak has more voxels far from any surface, so blur and partial
  // volume widen it least (small grains: the solid peak is the contaminated one).
  e.noise_sigma = *dark >= *bright ? e.sigma_void : e.sigma_solid;
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

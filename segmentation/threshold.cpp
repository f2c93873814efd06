#include "segmentation/threshold.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <fmt/core.h>
#include <limits>

#include "core/errors.hpp"

namespace tg {
namespace {

// First and last non-empty bins; throws for empty and constant histograms.
std::pair<int64_t, int64_t> trimmed_span(const std::vector<int64_t>& h, const char* who) {
  int64_t first = -1, last = -1;
  for (int64_t b = 0; b < int64_t(h.size()); ++b)
    if (h[size_t(b)] > 0) {
      if (first < 0) first = b;
      last = b;
    }
  if (first < 0) throw InputError(std::string(who) + " threshold: the histogram is empty (no voxels)");
  if (first == last)
    throw InputError(std::string(who) + " threshold: every voxel has the grey value " + std::to_string(first) +
                     "; a constant volume has no solid/void contrast to threshold");
  return {first, last};
}

// Two grey levels a < b only: the threshold is a (a void, b solid).
bool two_levels(const std::vector<int64_t>& h, int64_t first, int64_t last) {
  for (int64_t b = first + 1; b < last; ++b)
    if (h[size_t(b)] > 0) return false;
  return true;
}

ThresholdResult two_level_result(int64_t first, int64_t last, ThresholdMethod m) {
  ThresholdResult r;
  r.method = m;
  r.value = static_cast<uint16_t>(first);
  r.note = "only two grey levels (" + std::to_string(first) + ", " + std::to_string(last) +
           "): threshold set to the lower one, " + std::to_string(last) + " is solid";
  return r;
}

}  // namespace

const char* threshold_method_name(ThresholdMethod m) {
  switch (m) {
    case ThresholdMethod::moments: return "moments";
    case ThresholdMethod::otsu: return "otsu";
    case ThresholdMethod::manual: return "manual";
    case ThresholdMethod::local: return "local";
    case ThresholdMethod::midpoint: return "midpoint";
    case ThresholdMethod::automatic: return "auto";
  }
  return "?";
}

ThresholdMethod parse_threshold_method(const std::string& s) {
  if (s == "moments") return ThresholdMethod::moments;
  if (s == "otsu") return ThresholdMethod::otsu;
  if (s == "manual") return ThresholdMethod::manual;
  if (s == "local") return ThresholdMethod::local;
  if (s == "midpoint") return ThresholdMethod::midpoint;
  if (s == "auto") return ThresholdMethod::automatic;
  throw UsageError("threshold method '" + s + "': expected auto, moments, otsu, manual, local or midpoint");
}

std::vector<int64_t> histogram_u16(const Volume<uint16_t>& v, const std::vector<int64_t>* x0,
                                   const std::vector<int64_t>* x1) {
  const Shape s = v.shape();
  if ((x0 == nullptr) != (x1 == nullptr) || (x0 && (int64_t(x0->size()) != s.ny || int64_t(x1->size()) != s.ny)))
    throw UsageError("histogram: row spans need x0 and x1, one entry per row");
  const int nthreads = omp_get_max_threads();
  std::vector<std::vector<int64_t>> part(static_cast<size_t>(nthreads));
  const int64_t rows = s.nz * s.ny;
#pragma omp parallel num_threads(nthreads)
  {
    auto& h = part[size_t(omp_get_thread_num())];
    h.assign(65536, 0);
#pragma omp for schedule(static)
    for (int64_t r = 0; r < rows; ++r) {
      const int64_t j = r % s.ny;
      const uint16_t* row = v.data() + r * s.nx;
      const int64_t a = x0 ? (*x0)[size_t(j)] : 0, e = x1 ? (*x1)[size_t(j)] : s.nx;
      for (int64_t i = a; i < e; ++i) ++h[row[i]];
    }
  }
  std::vector<int64_t> hist(65536, 0);
  for (const auto& h : part)
    if (!h.empty())
      for (size_t b = 0; b < 65536; ++b) hist[b] += h[b];
  return hist;
}

ThresholdResult moments_threshold(const std::vector<int64_t>& hist) {
  const auto [first, last] = trimmed_span(hist, "moments");
  if (two_levels(hist, first, last)) return two_level_result(first, last, ThresholdMethod::moments);

  double total = 0;
  for (int64_t b = first; b <= last; ++b) total += double(hist[size_t(b)]);
  double m1 = 0, m2 = 0, m3 = 0;
  const double m0 = 1.0;
  for (int64_t b = first; b <= last; ++b) {
    const double p = double(hist[size_t(b)]) / total, i = double(b - first);
    m1 += i * p;
    m2 += i * i * p;
    m3 += i * i * i * p;
  }
  const double cd = m0 * m2 - m1 * m1;
  const double c0 = (-m2 * m2 + m1 * m3) / cd;
  const double c1 = (m0 * -m3 + m2 * m1) / cd;
  const double disc = c1 * c1 - 4.0 * c0;
  // With >= 3 grey levels cd > 0 and disc > 0 in exact arithmetic; guard the
  // rounding anyway rather than return a NaN threshold.
  if (!(cd > 0) || !(disc >= 0) || !std::isfinite(disc))
    throw InputError("moments threshold: the histogram's moments have no two-level solution (cd = " +
                     std::to_string(cd) + ", discriminant = " + std::to_string(disc) + ")");
  const double z0 = 0.5 * (-c1 - std::sqrt(disc));
  const double z1 = 0.5 * (-c1 + std::sqrt(disc));
  const double p0 = (z1 - m1) / (z1 - z0);

  ThresholdResult r;
  r.method = ThresholdMethod::moments;
  r.p0 = p0;
  r.z0 = z0 + double(first);
  r.z1 = z1 + double(first);
  double sum = 0;
  int64_t t = last;
  for (int64_t b = first; b <= last; ++b) {
    sum += double(hist[size_t(b)]) / total;
    if (sum > p0) {
      t = b;
      break;
    }
  }
  r.value = static_cast<uint16_t>(t);
  return r;
}

ThresholdResult otsu_threshold(const std::vector<int64_t>& hist) {
  const auto [first, last] = trimmed_span(hist, "otsu");
  if (two_levels(hist, first, last)) return two_level_result(first, last, ThresholdMethod::otsu);
  double n = 0, s = 0;
  for (int64_t b = first; b <= last; ++b) {
    n += double(hist[size_t(b)]);
    s += double(hist[size_t(b)]) * double(b - first);
  }
  // Between-class variance for class 0 = [first, t]: (s n0 - n s0)^2 / (n0 n1),
  // a form without the mean subtraction of the textbook one.
  double n0 = 0, s0 = 0, best = -1;
  int64_t t = first;
  for (int64_t b = first; b < last; ++b) {
    n0 += double(hist[size_t(b)]);
    s0 += double(hist[size_t(b)]) * double(b - first);
    const double n1 = n - n0;
    if (n0 == 0 || n1 == 0) continue;
    const double d = s0 * n - s * n0;
    const double var = d * d / (n0 * n1);
    if (var > best) {
      best = var;
      t = b;
    }
  }
  ThresholdResult r;
  r.method = ThresholdMethod::otsu;
  r.value = static_cast<uint16_t>(t);
  return r;
}

double separability(const std::vector<int64_t>& hist, uint16_t t) {
  double n = 0, s = 0, s2 = 0, n0 = 0, s0 = 0;
  for (size_t g = 0; g < hist.size(); ++g) {
    const double c = double(hist[g]), x = double(g);
    n += c, s += c * x, s2 += c * x * x;
    if (g <= t) n0 += c, s0 += c * x;
  }
  const double n1 = n - n0;
  if (n == 0 || n0 == 0 || n1 == 0) return 0.0;
  const double mu = s / n, var = s2 / n - mu * mu;
  if (!(var > 0)) return 0.0;
  const double d = s0 / n0 - (s - s0) / n1;
  return (n0 / n) * (n1 / n) * d * d / var;
}

// The plain mask is the graded one without a bright band (no grey is > 65535).
Volume<uint8_t> binarise(const Volume<uint16_t>& v, uint16_t t) { return binarise_graded(v, t, 65535); }

Volume<uint8_t> binarise(Volume<uint16_t>&& v, uint16_t t) { return binarise_graded(std::move(v), t, 65535); }

Volume<uint8_t> binarise_graded(const Volume<uint16_t>& v, uint16_t t, uint16_t tb) {
  Volume<uint8_t> m(v.shape(), v.geometry());
  const uint16_t* x = v.data();
  uint8_t* y = m.data();
  const int64_t n = v.size();
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) y[i] = uint8_t((x[i] > t) + (x[i] > tb));
  return m;
}

Volume<uint8_t> binarise_graded(Volume<uint16_t>&& v, uint16_t t, uint16_t tb) {
  return std::move(v).convert_in_place<uint8_t>([t, tb](uint16_t x) -> uint8_t { return uint8_t((x > t) + (x > tb)); });
}

double mean_above(const std::vector<int64_t>& hist, uint16_t t) {
  double n = 0, sum = 0;
  for (size_t g = size_t(t) + 1; g < hist.size(); ++g) {
    n += double(hist[g]);
    sum += double(hist[g]) * double(g);
  }
  return n > 0 ? sum / n : double(t);
}

namespace threshold_detail {

// Mode of the histogram's grey levels [lo, top]: 256 bins, each smoothed
// over 5, the fullest bin's mean grey.
double peak_mode(const std::vector<int64_t>& hist, size_t lo, size_t top) {
  constexpr int kBins = 256;
  const double w = std::max(1.0, double(top + 1 - lo) / kBins);
  std::vector<double> bin(kBins, 0.0), gsum(kBins, 0.0);
  for (size_t g = lo; g <= top && g < hist.size(); ++g) {
    const int b = std::min(kBins - 1, int(double(g - lo) / w));
    bin[size_t(b)] += double(hist[g]);
    gsum[size_t(b)] += double(hist[g]) * double(g);
  }
  int best = 0;
  double best_count = -1;
  for (int b = 0; b < kBins; ++b) {
    double c = 0;
    for (int d = std::max(0, b - 2); d <= std::min(kBins - 1, b + 2); ++d) c += bin[size_t(d)];
    if (c > best_count) best_count = c, best = b;
  }
  return bin[size_t(best)] > 0 ? gsum[size_t(best)] / bin[size_t(best)] : double(lo) + (best + 0.5) * w;
}

}  // namespace threshold_detail

SolidPeak solid_peak(const std::vector<int64_t>& hist, uint16_t t) {
  const size_t lo = size_t(t) + 1;
  int64_t n = 0;
  for (size_t g = lo; g < hist.size(); ++g) n += hist[g];
  if (n == 0) return {double(t), 0.0};
  // Top: the 99.9th percentile of the solid voxels (saturated outliers out).
  size_t top = lo;
  for (int64_t c = 0; top < hist.size(); ++top)
    if ((c += hist[top]) >= n - n / 1000) break;
  SolidPeak p;
  p.mode = threshold_detail::peak_mode(hist, lo, top);
  // Median of the deviations above the mode.
  const size_t m0 = size_t(std::ceil(p.mode));
  int64_t above = 0;
  for (size_t g = m0; g < hist.size(); ++g) above += hist[g];
  int64_t c = 0;
  for (size_t g = m0; g < hist.size(); ++g)
    if ((c += hist[g]) * 2 >= above) {
      p.sigma = (double(g) - p.mode) / 0.6745;
      break;
    }
  p.sigma = std::max(0.0, p.sigma);
  return p;
}

namespace threshold_detail {

// Mean shift from a peak's smoothed mode m: m <- the mean grey of the
// voxels within m +- sigma, until it moves less than 0.1 grey (at most 20
// steps). The smoothed histogram's fullest bin leans towards the side where
// partial-volume voxels add to the peak's flank (~1 % of the contrast at
// CNR 13, blind sweep); a window as wide as the noise, centred on the
// peak, holds almost only the peak itself.
double refine_mode(const std::vector<int64_t>& hist, double m, double sigma) {
  if (!(sigma > 0)) return m;
  for (int step = 0; step < 20; ++step) {
    const auto lo = size_t(std::max(0.0, std::ceil(m - sigma)));
    const auto hi = size_t(std::min(double(hist.size() - 1), std::floor(m + sigma)));
    double n = 0, sum = 0;
    for (size_t g = lo; g <= hi; ++g) n += double(hist[g]), sum += double(hist[g]) * double(g);
    if (n == 0) break;
    const double next = sum / n;
    const bool done = std::abs(next - m) < 0.1;
    m = next;
    if (done) break;
  }
  return m;
}

}  // namespace threshold_detail

PhaseLevels phase_levels(std::vector<int64_t> hist, int64_t clipped_zeros) {
  PhaseLevels r;
  // A binary or few-level image (under 4 grey levels, as screen_levels
  // calls it: a pre-thresholded scan, 0 / 255 or 0 / 65535): its zeros are
  // a phase, not a mask, and each phase is its most populated level, without
  // noise.
  int distinct = 0;
  for (size_t b = 0; b < hist.size() && distinct < 4; ++b) distinct += hist[b] > 0;
  if (distinct < 4) {
    r.threshold = moments_threshold(hist).value;
    const auto mode = [&](size_t lo, size_t hi) {  // the fullest bin of [lo, hi)
      size_t m = lo;
      for (size_t g = lo; g < hi; ++g)
        if (hist[g] > hist[m]) m = g;
      return double(m);
    };
    r.void_level = mode(0, size_t(r.threshold) + 1);
    r.solid = mode(size_t(r.threshold) + 1, hist.size());
    return r;
  }
  hist[0] = 0;  // pre-masked voxels (docs/real_scans.md) are no phase
  r.threshold = moments_threshold(hist).value;
  const SolidPeak solid = solid_peak(hist, r.threshold);
  r.solid = threshold_detail::refine_mode(hist, solid.mode, solid.sigma);
  r.solid_sigma = solid.sigma;
  // The void peak: from the 0.1th percentile of the voxels at or below t
  // (dark outliers out) to t; its noise sigma from its lower side, the side
  // without partial volume (as solid_peak takes the solid's upper side).
  const size_t t = r.threshold;
  int64_t n = 0;
  for (size_t g = 1; g <= t; ++g) n += hist[g];
  if (n == 0) {
    r.void_level = double(t);
    return r;
  }
  size_t lo = 1;
  for (int64_t c = 0; lo < t; ++lo)
    if ((c += hist[lo]) > n / 1000) break;
  const double m = threshold_detail::peak_mode(hist, lo, t);
  int64_t below = clipped_zeros;  // void voxels clipped at 0 lie below every other
  for (size_t g = 1; g <= size_t(m); ++g) below += hist[g];
  double sigma = m / 0.6745;  // the median among the clipped zeros: at least this
  int64_t c = 0;
  for (size_t g = size_t(m); g >= 1; --g)
    if ((c += hist[g]) * 2 >= below) {
      sigma = (m - double(g)) / 0.6745;
      break;
    }
  r.void_level = threshold_detail::refine_mode(hist, m, sigma);
  r.void_sigma = std::max(0.0, sigma);
  return r;
}

double gaussian_tail_sigmas(double p) {
  if (!(p > 0) || p >= 0.5) return p > 0 ? 0.0 : std::numeric_limits<double>::infinity();
  double lo = 0, hi = 40;  // 0.5 erfc(40 / sqrt 2) ~ 4e-350: below any p a double holds
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

ThresholdResult auto_threshold(const std::vector<int64_t>& hist) {
  ThresholdResult r = moments_threshold(hist);  // its p0, z0, z1 stay in the summary
  const PhaseLevels pl = phase_levels(hist);
  AutoChoice& a = r.automatic;
  a.void_level = pl.void_level;
  a.solid_level = pl.solid;
  a.void_sigma = pl.void_sigma;
  a.solid_sigma = pl.solid_sigma;
  a.midpoint = 0.5 * (pl.void_level + pl.solid);
  a.moments = r.value;
  for (size_t g = 1; g <= size_t(r.value) && g < hist.size(); ++g) a.void_voxels += hist[g];
  a.k_sigmas = a.void_voxels > 1 ? gaussian_tail_sigmas(1.0 / double(a.void_voxels)) : 0.0;
  a.sigma = std::max(a.void_sigma, a.solid_sigma);
  a.floor = a.void_level + a.k_sigmas * a.sigma;
  const double t = std::max(a.midpoint, std::min(a.floor, double(a.moments)));
  const double margin = a.sigma > 0 ? (a.midpoint - a.void_level) / a.sigma : 0.0;
  r.method = ThresholdMethod::automatic;
  if (a.floor <= a.midpoint || double(a.moments) <= a.midpoint) {
    a.chosen = "midpoint";
    r.value = uint16_t(std::clamp(std::lround(a.midpoint), 0L, 65535L));
    a.why = a.floor <= a.midpoint
                ? fmt::format("midpoint: {:.1f} noise sigmas above the void peak, at least k = {:.2f} (k: pure noise lifts about one "
                              "of the {} void voxels that far)",
                              margin, a.k_sigmas, a.void_voxels)
                : fmt::format("midpoint: Tsai's level ({}) is below it; nothing higher to fall back on", a.moments);
  } else if (a.floor >= double(a.moments)) {
    a.chosen = "moments";
    r.value = a.moments;
    a.why = fmt::format("moments: the midpoint is only {:.1f} noise sigmas above the void peak, under k = {:.2f} "
                        "(k: pure noise lifts about one of the {} void voxels that far); the floor k sigmas above the "
                        "void peak is above Tsai's level, which is kept",
                        margin, a.k_sigmas, a.void_voxels);
  } else {
    a.chosen = "floor";
    r.value = uint16_t(std::clamp(std::lround(t), 0L, 65535L));
    a.why = fmt::format("floor: the midpoint is only {:.1f} noise sigmas above the void peak, under k = {:.2f}; "
                        "the threshold is k sigmas above the void peak, between the midpoint and Tsai's level",
                        margin, a.k_sigmas);
  }
  return r;
}

}  // namespace tg

#include "segmentation/normalise.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/errors.hpp"

namespace tg {
namespace {

constexpr int64_t kFloatBins = int64_t{1} << 20;

struct MinMax {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  int64_t finite = 0;
};

MinMax finite_min_max(const float* x, int64_t n) {
  MinMax r;
  double lo = r.lo, hi = r.hi;
  int64_t finite = 0;
#pragma omp parallel for schedule(static) reduction(min : lo) reduction(max : hi) reduction(+ : finite)
  for (int64_t i = 0; i < n; ++i) {
    const float v = x[i];
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, double(v));
    hi = std::max(hi, double(v));
    ++finite;
  }
  r.lo = lo;
  r.hi = hi;
  r.finite = finite;
  return r;
}

// Value below which `rank` (0 <= rank <= total) of the counts lie, linear
// inside the bin that holds it.
double percentile_from_histogram(const std::vector<int64_t>& h, double rank, double lo, double width) {
  double cum = 0;
  for (size_t b = 0; b < h.size(); ++b) {
    const double c = double(h[b]);
    if (c > 0 && cum + c >= rank) return lo + width * (double(b) + (rank - cum) / c);
    cum += c;
  }
  return lo + width * double(h.size());
}

}  // namespace

NormaliseRange auto_range(const Volume<float>& v) {
  const int64_t n = v.size();
  if (n == 0) throw InputError("auto range: the volume is empty");
  const MinMax mm = finite_min_max(v.data(), n);
  if (mm.finite == 0) throw InputError("auto range: the volume has no finite value");
  if (!(mm.hi > mm.lo))
    throw InputError("auto range: every finite voxel has the value " + std::to_string(mm.lo) +
                     "; nothing to map to 16 bits (give --range LO,HI)");

  // Histogram of 2^20 bins on [min, max]; per-thread partials summed in a
  // fixed order (integer sums, so the order does not matter anyway).
  const double width = (mm.hi - mm.lo) / double(kFloatBins);
  const double inv = 1.0 / width;
  const int nthreads = omp_get_max_threads();
  std::vector<std::vector<int64_t>> part(static_cast<size_t>(nthreads));
  const float* x = v.data();
#pragma omp parallel num_threads(nthreads)
  {
    auto& h = part[static_cast<size_t>(omp_get_thread_num())];
    h.assign(kFloatBins, 0);
#pragma omp for schedule(static)
    for (int64_t i = 0; i < n; ++i) {
      const float f = x[i];
      if (!std::isfinite(f)) continue;
      const int64_t b = std::min<int64_t>(kFloatBins - 1, static_cast<int64_t>((double(f) - mm.lo) * inv));
      ++h[static_cast<size_t>(b)];
    }
  }
  std::vector<int64_t> hist(kFloatBins, 0);
  for (const auto& h : part)
    if (!h.empty())
      for (int64_t b = 0; b < kFloatBins; ++b) hist[size_t(b)] += h[size_t(b)];

  const double total = double(mm.finite);
  NormaliseRange r;
  r.lo = percentile_from_histogram(hist, total * kAutoLowPercent / 100.0, mm.lo, width);
  r.hi = percentile_from_histogram(hist, total * kAutoHighPercent / 100.0, mm.lo, width);
  r.how = "auto: " + std::to_string(kAutoLowPercent) + " % / " + std::to_string(kAutoHighPercent) +
          " % percentiles of " + std::to_string(mm.finite) + " finite voxels (min " + std::to_string(mm.lo) +
          ", max " + std::to_string(mm.hi) + ")";
  if (!(r.hi > r.lo)) {
    // Almost every voxel has one value: fall back to the full finite range.
    r.lo = mm.lo;
    r.hi = mm.hi;
    r.how += "; percentiles coincide, using min..max";
  }
  return r;
}

Volume<uint16_t> normalise_to_u16(const Volume<float>& v, NormaliseRange range) {
  if (!std::isfinite(range.lo) || !std::isfinite(range.hi) || !(range.hi > range.lo))
    throw UsageError("normalise: the range must satisfy LO < HI, both finite (got " + std::to_string(range.lo) +
                     ", " + std::to_string(range.hi) + ")");
  Volume<uint16_t> out(v.shape(), v.geometry());
  const int64_t n = v.size();
  const double lo = range.lo, scale = 65535.0 / (range.hi - range.lo);
  const float* x = v.data();
  uint16_t* y = out.data();
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) {
    const double t = (double(x[i]) - lo) * scale;
    // Written so that NaN fails both tests and maps to 0.
    y[i] = t >= 65535.0 ? uint16_t{65535} : t > 0.0 ? static_cast<uint16_t>(t + 0.5) : uint16_t{0};
  }
  return out;
}

}  // namespace tg

#include "core/stats.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tg {

double VolumeStats::percentile(double p) const {
  if (finite == 0 || hist.empty()) return 0;
  const double target = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(finite);
  int64_t cum = 0;
  for (size_t b = 0; b < hist.size(); ++b) {
    cum += hist[b];
    if (static_cast<double>(cum) >= target && hist[b] > 0)
      return hist_width == 1 && hist_lo == std::floor(hist_lo) ? hist_lo + static_cast<double>(b)
                                                                : hist_lo + (static_cast<double>(b) + 0.5) * hist_width;
  }
  return max;
}

namespace {

template <class T>
VolumeStats stats_of(const Volume<T>& v) {
  VolumeStats s;
  s.voxels = v.size();
  const T* p = v.data();
  const int64_t n = v.size();
  // Pass 1: min, max, count, sum (per-thread partials merged in thread order: deterministic for a fixed
  // thread count; sums of integers are exact in double up to 2^53 so integer volumes never differ).
  double mn = std::numeric_limits<double>::infinity(), mx = -mn;
  int64_t fin = 0;
  double sum = 0;
#pragma omp parallel for schedule(static) reduction(min : mn) reduction(max : mx) reduction(+ : fin, sum)
  for (int64_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(p[i]);
    if constexpr (std::is_floating_point_v<T>)
      if (!std::isfinite(x)) continue;
    mn = std::min(mn, x);
    mx = std::max(mx, x);
    sum += x;
    ++fin;
  }
  s.finite = fin;
  s.nonfinite = n - fin;
  if (fin == 0) return s;
  s.min = mn;
  s.max = mx;
  s.mean = sum / static_cast<double>(fin);
  // Pass 2: variance about the mean and the histogram.
  const bool exact = !std::is_floating_point_v<T> && sizeof(T) <= 2;
  const int64_t nbins = exact ? static_cast<int64_t>(mx - mn) + 1 : 4096;
  s.hist_lo = exact ? mn : mn;
  s.hist_width = exact ? 1.0 : std::max((mx - mn) / static_cast<double>(nbins), std::numeric_limits<double>::min());
  s.hist.assign(static_cast<size_t>(nbins), 0);
  double var = 0;
  const int nt = omp_get_max_threads();
  std::vector<std::vector<int64_t>> part(static_cast<size_t>(nt), std::vector<int64_t>(static_cast<size_t>(nbins), 0));
#pragma omp parallel reduction(+ : var)
  {
    auto& h = part[static_cast<size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (int64_t i = 0; i < n; ++i) {
      const double x = static_cast<double>(p[i]);
      if constexpr (std::is_floating_point_v<T>)
        if (!std::isfinite(x)) continue;
      var += (x - s.mean) * (x - s.mean);
      const int64_t b = std::min<int64_t>(nbins - 1, static_cast<int64_t>((x - s.hist_lo) / s.hist_width));
      ++h[static_cast<size_t>(b)];
    }
  }
  for (const auto& h : part)
    for (int64_t b = 0; b < nbins; ++b) s.hist[static_cast<size_t>(b)] += h[static_cast<size_t>(b)];
  s.stddev = std::sqrt(var / static_cast<double>(fin));
  if (exact) {
    s.count_at_min = s.hist.front();
    s.count_at_max = s.hist.back();
  }
  if constexpr (std::is_same_v<T, uint32_t>) {
    if (mx < 2e8) {  // a bitmap of at most 25 MB
      std::vector<uint8_t> seen(static_cast<size_t>(mx) + 1, 0);
      for (int64_t i = 0; i < n; ++i) seen[p[i]] = 1;
      int64_t d = 0;
      for (size_t l = 1; l < seen.size(); ++l) d += seen[l];
      s.distinct_nonzero = d;
    }
  }
  return s;
}

}  // namespace

VolumeStats compute_stats(const AnyVolume& v) {
  return std::visit([](const auto& vol) { return stats_of(vol); }, v);
}

}  // namespace tg

#include "segmentation/rings.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "core/errors.hpp"

namespace tg {
namespace {

template <class T>
RingResult remove_rings_impl(Volume<T>& v, const RingOptions& o) {
  if (o.window < 3 || o.window % 2 == 0) throw UsageError("rings: the median window must be odd and >= 3 bins");
  if (!(o.min_z > 0) || !std::isfinite(o.min_z)) throw UsageError("rings: min_z must be > 0");
  RingResult res;
  const Shape s = v.shape();
  if (s.empty()) return res;
  res.centre_y = o.centre_y >= 0 ? o.centre_y : 0.5 * double(s.ny);
  res.centre_x = o.centre_x >= 0 ? o.centre_x : 0.5 * double(s.nx);
  // The bin of each pixel of a slice.
  const int64_t sl = s.slice_voxels();
  std::vector<int32_t> bin(static_cast<size_t>(sl));
  int32_t nb = 0;
  for (int64_t j = 0; j < s.ny; ++j)
    for (int64_t i = 0; i < s.nx; ++i) {
      const double dy = double(j) + 0.5 - res.centre_y, dx = double(i) + 0.5 - res.centre_x;
      const auto b = static_cast<int32_t>(std::floor(std::hypot(dy, dx)));
      bin[size_t(j * s.nx + i)] = b;
      nb = std::max(nb, b + 1);
    }
  res.bins = nb;
  // Sums of grey and grey^2 per slice and bin, reduced in slice order.
  std::vector<double> sum(size_t(s.nz) * size_t(nb), 0.0), sq(sum.size(), 0.0);
  const T* V = v.data();
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < s.nz; ++k) {
    double* a = &sum[size_t(k) * size_t(nb)];
    double* q = &sq[size_t(k) * size_t(nb)];
    const T* row = V + k * sl;
    for (int64_t p = 0; p < sl; ++p) {
      const double g = double(row[p]);
      a[bin[size_t(p)]] += g;
      q[bin[size_t(p)]] += g * g;
    }
  }
  std::vector<double> count(size_t(nb), 0.0), mean(size_t(nb), 0.0), var(size_t(nb), 0.0);
  for (int64_t p = 0; p < sl; ++p) count[size_t(bin[size_t(p)])] += double(s.nz);
  for (int32_t b = 0; b < nb; ++b) {
    double a = 0, q = 0;
    for (int64_t k = 0; k < s.nz; ++k) a += sum[size_t(k) * size_t(nb) + size_t(b)], q += sq[size_t(k) * size_t(nb) + size_t(b)];
    if (count[size_t(b)] == 0) continue;
    mean[size_t(b)] = a / count[size_t(b)];
    var[size_t(b)] = std::max(0.0, q / count[size_t(b)] - mean[size_t(b)] * mean[size_t(b)]);
  }
  sum = {};
  sq = {};
  // Offsets: the profile against its running median (bins past the ends
  // take the end bin's mean).
  res.offset.assign(size_t(nb), 0.0);
  const int h = o.window / 2;
  std::vector<double> w(size_t(o.window));
  for (int32_t b = 0; b < nb; ++b) {
    // A window reaching a bin of one value throughout (outside a field of
    // view, set to a constant) would read the step there as a ring.
    bool flat = false;
    for (int d = -h; d <= h; ++d) flat = flat || var[size_t(std::clamp(b + d, 0, nb - 1))] == 0;
    if (flat) continue;
    for (int d = -h; d <= h; ++d) w[size_t(d + h)] = mean[size_t(std::clamp(b + d, 0, nb - 1))];
    std::nth_element(w.begin(), w.begin() + h, w.end());
    const double off = mean[size_t(b)] - w[size_t(h)];
    const double se = std::sqrt(var[size_t(b)] / count[size_t(b)]);
    if (std::abs(off) > o.min_z * se) {  // se > 0: the window holds no flat bin
      res.offset[size_t(b)] = off;
      ++res.rings;
      res.max_offset = std::max(res.max_offset, std::abs(off));
    }
  }
  if (res.rings == 0) return res;
  T* W = v.data();
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < s.nz; ++k) {
    T* row = W + k * sl;
    for (int64_t p = 0; p < sl; ++p) {
      const double off = res.offset[size_t(bin[size_t(p)])];
      if (off == 0) continue;
      if constexpr (std::is_same_v<T, uint16_t>)
        row[p] = static_cast<uint16_t>(std::clamp(std::lround(double(row[p]) - off), 0L, 65535L));
      else
        row[p] = static_cast<T>(double(row[p]) - off);
    }
  }
  return res;
}

}  // namespace

RingResult remove_rings(Volume<uint16_t>& v, const RingOptions& o) { return remove_rings_impl(v, o); }
RingResult remove_rings(Volume<float>& v, const RingOptions& o) { return remove_rings_impl(v, o); }

}  // namespace tg

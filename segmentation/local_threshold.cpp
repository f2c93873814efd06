#include "segmentation/local_threshold.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "segmentation/threshold.hpp"

namespace tg {
namespace {

constexpr int64_t kBlockBins = 4096;  // bins of a block's histogram
constexpr double kMinSeparability = 0.8;
constexpr double kMinPhase = 0.05;

// Blocks along an axis of n voxels: round(n / w) of them (at least 1),
// block b covering [b n / nb, (b + 1) n / nb): edges within one voxel of
// each other, no sliver at the end.
int64_t blocks(int64_t n, int64_t w) { return std::max<int64_t>(1, (n + w / 2) / w); }
int64_t bound(int64_t b, int64_t n, int64_t nb) { return b * n / nb; }

// Interpolation along one axis: the threshold at coordinate p is
// (1 - w) t[b0] + w t[b0 + 1], w in [0, 1] between two block centres and
// beyond the outer ones (then < 0 or > 1) linear extrapolation; blk is the
// block holding p.
struct Axis {
  std::vector<int32_t> b0, blk;
  std::vector<float> w;
};

Axis axis(int64_t n, int64_t nb) {
  std::vector<double> c(static_cast<size_t>(nb));
  for (int64_t b = 0; b < nb; ++b) c[size_t(b)] = 0.5 * double(bound(b, n, nb) + bound(b + 1, n, nb) - 1);
  Axis a;
  a.b0.resize(size_t(n));
  a.blk.resize(size_t(n));
  a.w.resize(size_t(n));
  // Between the outer centres and the faces (half a block) the line of the
  // two outer blocks is extended: a drift keeps its slope to the faces.
  int64_t b = 0;
  for (int64_t p = 0; p < n; ++p) {
    while (b + 2 < nb && c[size_t(b + 1)] <= double(p)) ++b;
    a.b0[size_t(p)] = int32_t(b);
    a.w[size_t(p)] = nb < 2 ? 0.f : float((double(p) - c[size_t(b)]) / (c[size_t(b + 1)] - c[size_t(b)]));
  }
  for (int64_t q = 0; q < nb; ++q)
    for (int64_t p = bound(q, n, nb); p < bound(q + 1, n, nb); ++p) a.blk[size_t(p)] = int32_t(q);
  return a;
}

// The thresholds of row (k, j) at every x: bilinear in (z, y) per block
// column, then linear along x.
class RowThresholds {
 public:
  RowThresholds(const LocalThreshold& lt, const Shape& s)
      : lt_(lt), s_(s), az_(axis(s.nz, lt.nbz)), ay_(axis(s.ny, lt.nby)), ax_(axis(s.nx, lt.nbx)) {}
  void fill(int64_t k, int64_t j, std::vector<float>& tb, std::vector<float>& t) const {
    const int64_t z0 = az_.b0[size_t(k)], y0 = ay_.b0[size_t(j)];
    const int64_t z1 = std::min(z0 + 1, lt_.nbz - 1), y1 = std::min(y0 + 1, lt_.nby - 1);
    const float wz = az_.w[size_t(k)], wy = ay_.w[size_t(j)];
    tb.resize(size_t(lt_.nbx));
    for (int64_t b = 0; b < lt_.nbx; ++b) {
      auto at = [&](int64_t z, int64_t y) { return lt_.t[size_t((z * lt_.nby + y) * lt_.nbx + b)]; };
      tb[size_t(b)] = (1 - wz) * ((1 - wy) * at(z0, y0) + wy * at(z0, y1)) + wz * ((1 - wy) * at(z1, y0) + wy * at(z1, y1));
    }
    t.resize(size_t(s_.nx));
    for (int64_t i = 0; i < s_.nx; ++i) {
      const int64_t b0 = ax_.b0[size_t(i)], b1 = std::min(b0 + 1, lt_.nbx - 1);
      const float w = ax_.w[size_t(i)];
      t[size_t(i)] = (1 - w) * tb[size_t(b0)] + w * tb[size_t(b1)];
    }
  }

 private:
  const LocalThreshold& lt_;
  Shape s_;
  Axis az_, ay_, ax_;
};

}  // namespace

int64_t default_local_window(double r) { return std::max<int64_t>(32, int64_t(std::lround(4.0 * r))); }

LocalThreshold local_moments_thresholds(const Volume<uint16_t>& grey, const FieldOfView& fov,
                                        const std::vector<int64_t>& screened, int64_t window, uint16_t fallback) {
  if (window < 2) throw UsageError("segment: the local threshold's window must be >= 2 voxels");
  const Shape s = grey.shape();
  LocalThreshold lt;
  lt.window = window;
  lt.nbz = blocks(s.nz, window), lt.nby = blocks(s.ny, window), lt.nbx = blocks(s.nx, window);
  const int64_t nb = lt.nbz * lt.nby * lt.nbx;
  // The block histograms span the screened global histogram's range
  // [lo, hi] in at most 4096 bins; the levels outside it are exactly those
  // left out by screen_levels (pre-masked or clipped zeros, saturation).
  int64_t lo = -1, hi = -1;
  for (int64_t g = 0; g < 65536; ++g)
    if (screened[size_t(g)]) {
      if (lo < 0) lo = g;
      hi = g;
    }
  if (lo < 0) throw InputError("segment: no grey level left to threshold");
  int shift = 0;
  while (((hi - lo) >> shift) >= kBlockBins) ++shift;
  const Axis ax = axis(s.nx, lt.nbx);
  lt.t.assign(size_t(nb), 0.f);
  std::vector<uint8_t> known(size_t(nb), 0);
  int64_t trusted = 0;
  // Each (bz, by) row of blocks is one iteration: its histograms are made,
  // thresholded and dropped by one thread (memory: nbx histograms per
  // thread, not one per block of the volume).
#pragma omp parallel reduction(+ : trusted)
  {
    std::vector<int64_t> hist(size_t(lt.nbx * kBlockBins));
#pragma omp for schedule(static)
    for (int64_t q = 0; q < lt.nbz * lt.nby; ++q) {
      const int64_t bz = q / lt.nby, by = q % lt.nby;
      std::fill(hist.begin(), hist.end(), int64_t(0));
      for (int64_t k = bound(bz, s.nz, lt.nbz); k < bound(bz + 1, s.nz, lt.nbz); ++k)
        for (int64_t j = bound(by, s.ny, lt.nby); j < bound(by + 1, s.ny, lt.nby); ++j) {
          const uint16_t* row = &grey(k, j, 0);
          const int64_t a = fov.active ? fov.x0[size_t(j)] : 0, e = fov.active ? fov.x1[size_t(j)] : s.nx;
          for (int64_t i = a; i < e; ++i) {
            const int64_t g = row[i];
            if (g >= lo && g <= hi) ++hist[size_t(ax.blk[size_t(i)] * kBlockBins + ((g - lo) >> shift))];
          }
        }
      // Own thresholds of the bimodal blocks.
      for (int64_t bx = 0; bx < lt.nbx; ++bx) {
        const std::vector<int64_t> h(hist.begin() + bx * kBlockBins, hist.begin() + (bx + 1) * kBlockBins);
        int64_t n = 0;
        for (auto c : h) n += c;
        if (n < 64) continue;
        ThresholdResult r;
        try {
          r = moments_threshold(h);
        } catch (const InputError&) {
          continue;  // a constant block
        }
        if (!r.note.empty()) continue;  // two grey levels only
        int64_t below = 0;
        for (int64_t g = 0; g <= r.value; ++g) below += h[size_t(g)];
        const double f0 = double(below) / double(n);
        if (std::min(f0, 1 - f0) < kMinPhase || separability(h, r.value) < kMinSeparability) continue;
        const int64_t blk = q * lt.nbx + bx;
        lt.t[size_t(blk)] = float(lo + (int64_t(r.value) << shift) + (int64_t(1) << shift) - 1);
        known[size_t(blk)] = 1;
        ++trusted;
      }
    }
  }
  lt.trusted = trusted;
  if (lt.trusted == 0) {
    lt.t.assign(size_t(nb), float(fallback));
    lt.min = lt.max = float(fallback);
    lt.note = "local threshold: no block of " + std::to_string(window) +
              " voxels is bimodal; the global threshold is used everywhere";
    return lt;
  }
  // Untrusted blocks: the mean of their known face neighbours, layer by layer.
  const int64_t dz = lt.nby * lt.nbx, dy = lt.nbx;
  for (bool more = true; more;) {
    more = false;
    std::vector<uint8_t> next = known;
    std::vector<float> tn = lt.t;
    for (int64_t b = 0; b < nb; ++b) {
      if (known[size_t(b)]) continue;
      const int64_t bz = b / dz, by = (b / dy) % lt.nby, bx = b % lt.nbx;
      double sum = 0;
      int cnt = 0;
      auto take = [&](bool ok, int64_t o) {
        if (ok && known[size_t(o)]) sum += lt.t[size_t(o)], ++cnt;
      };
      take(bz > 0, b - dz), take(bz + 1 < lt.nbz, b + dz);
      take(by > 0, b - dy), take(by + 1 < lt.nby, b + dy);
      take(bx > 0, b - 1), take(bx + 1 < lt.nbx, b + 1);
      if (cnt) tn[size_t(b)] = float(sum / cnt), next[size_t(b)] = 1, ++lt.filled, more = true;
    }
    known.swap(next);
    lt.t.swap(tn);
  }
  const auto [mn, mx] = std::minmax_element(lt.t.begin(), lt.t.end());
  lt.min = *mn, lt.max = *mx;
  return lt;
}

namespace {

// Row by row (in parallel): out[i] = 1 where voxel i of the row is inside
// the field of view and above its interpolated threshold, else 0. `out` may
// be the grey row itself (each voxel is read before it is written).
template <class Out>
void decide_rows(const Volume<uint16_t>& grey, const LocalThreshold& lt, const FieldOfView& fov, Out* out) {
  const Shape s = grey.shape();
  const RowThresholds rt(lt, s);
  const int64_t rows = s.nz * s.ny;
#pragma omp parallel
  {
    std::vector<float> tb, t;
#pragma omp for schedule(static)
    for (int64_t r = 0; r < rows; ++r) {
      const int64_t k = r / s.ny, j = r % s.ny;
      rt.fill(k, j, tb, t);
      const uint16_t* x = grey.data() + r * s.nx;
      Out* y = out + r * s.nx;
      const int64_t a = fov.active ? fov.x0[size_t(j)] : 0, e = fov.active ? fov.x1[size_t(j)] : s.nx;
      for (int64_t i = 0; i < s.nx; ++i) y[i] = (i >= a && i < e && float(x[i]) > t[size_t(i)]) ? 1 : 0;
    }
  }
}

}  // namespace

Volume<uint8_t> binarise_local(const Volume<uint16_t>& grey, const LocalThreshold& lt, const FieldOfView& fov) {
  Volume<uint8_t> m(grey.shape(), grey.geometry());
  decide_rows(grey, lt, fov, m.data());
  return m;
}

Volume<uint8_t> binarise_local(Volume<uint16_t>&& grey, const LocalThreshold& lt, const FieldOfView& fov) {
  // Pass 1 writes 0/1 into the grey levels themselves; pass 2 is the plain
  // in-place binarisation at 0 (no second volume).
  decide_rows(grey, lt, fov, grey.data());
  return binarise(std::move(grey), 0);
}

}  // namespace tg

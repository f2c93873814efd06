#include "segmentation/grain_levels.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/errors.hpp"
#include "segmentation/split_labels.hpp"

namespace tg {
namespace {

// Rounded to the nearest level (halves up) and clipped; no libm call (the
// passes round every voxel six times).
inline uint16_t to_u16(float v) { return uint16_t(std::clamp(v, 0.0f, 65535.0f) + 0.5f); }

// Separable passes over a (z, y, x) volume, the faces repeated. `fold`
// folds a line's taps: Gaussian (weighted sum) or maximum. z reads `in` and
// writes `out` (slice by slice: whole slices stay in cache); y and x work
// in place on `out` from a copy of the slice or row.
template <class Fold>
void separable(const Volume<uint16_t>& in, Volume<uint16_t>& out, int r, Fold fold) {
  const Shape s = in.shape();
  const int64_t nz = s.nz, ny = s.ny, nx = s.nx, sl = ny * nx;
  const uint16_t* I = in.data();
  uint16_t* O = out.data();
#pragma omp parallel
  {
    std::vector<float> acc(static_cast<size_t>(sl));
    std::vector<float> buf(static_cast<size_t>(std::max<int64_t>(sl, nx + 2 * r)));
#pragma omp for schedule(static)
    for (int64_t z = 0; z < nz; ++z) {
      // z: the 2r + 1 slices around z
      for (int t = -r; t <= r; ++t) {
        const uint16_t* src = I + std::clamp<int64_t>(z + t, 0, nz - 1) * sl;
        fold.slice(acc.data(), src, sl, t + r);
      }
      // y: rows of acc around each row
      std::copy(acc.begin(), acc.end(), buf.begin());
      for (int64_t y = 0; y < ny; ++y) {
        float* a = acc.data() + y * nx;
        for (int t = -r; t <= r; ++t) fold.row(a, buf.data() + std::clamp<int64_t>(y + t, 0, ny - 1) * nx, nx, t + r);
      }
      // x: each row padded by its end voxels, the taps shifted over the
      // row (vectorised), into the row's own place in acc
      uint16_t* o = O + z * sl;
      for (int64_t y = 0; y < ny; ++y) {
        float* a = acc.data() + y * nx;
        float* p = buf.data();
        std::fill(p, p + r, a[0]);
        std::copy(a, a + nx, p + r);
        std::fill(p + r + nx, p + nx + 2 * r, a[nx - 1]);
        for (int t = 0; t <= 2 * r; ++t) fold.row(a, p + t, nx, t);
        for (int64_t x = 0; x < nx; ++x) o[y * nx + x] = to_u16(a[x]);
      }
    }
  }
}

struct GaussFold {
  const std::vector<float>& w;
  void slice(float* acc, const uint16_t* src, int64_t n, int t) const {
    const float wt = w[size_t(t)];
    if (t == 0)
      for (int64_t i = 0; i < n; ++i) acc[i] = wt * float(src[i]);
    else
      for (int64_t i = 0; i < n; ++i) acc[i] += wt * float(src[i]);
  }
  // y and x passes: tap t of `src` into a (tap 0 overwrites it).
  void row(float* a, const float* src, int64_t n, int t) const {
    const float wt = w[size_t(t)];
    if (t == 0)
      for (int64_t i = 0; i < n; ++i) a[i] = wt * src[i];
    else
      for (int64_t i = 0; i < n; ++i) a[i] += wt * src[i];
  }
};

struct MaxFold {
  void slice(float* acc, const uint16_t* src, int64_t n, int t) const {
    if (t == 0)
      for (int64_t i = 0; i < n; ++i) acc[i] = float(src[i]);
    else
      for (int64_t i = 0; i < n; ++i) acc[i] = std::max(acc[i], float(src[i]));
  }
  void row(float* a, const float* src, int64_t n, int t) const {
    if (t == 0)
      for (int64_t i = 0; i < n; ++i) a[i] = src[i];
    else
      for (int64_t i = 0; i < n; ++i) a[i] = std::max(a[i], src[i]);
  }
};

}  // namespace

DimPopulation dim_population(const std::vector<int64_t>& h, const GrainLevelsInput& in, double min_prominence) {
  DimPopulation out;
  const double V = in.void_level, P = in.solid_level, span = P - V;
  if (!(span > 0) || h.empty()) return out;
  const double b = std::max(1.0, span / 40.0);
  const int nb = 40;
  std::vector<double> c(size_t(nb), 0.0);
  for (int k = 0; k < nb; ++k) {
    const int64_t g0 = std::max<int64_t>(0, std::llround(V + k * b)), g1 = std::llround(V + (k + 1) * b);
    for (int64_t g = g0; g < g1 && g < int64_t(h.size()); ++g) c[size_t(k)] += double(h[size_t(g)]);
  }
  std::vector<double> a(c.size(), 0.0);  // 3-bin average
  for (int k = 0; k < nb; ++k)
    a[size_t(k)] = (c[size_t(std::max(0, k - 1))] + c[size_t(k)] + c[size_t(std::min(nb - 1, k + 1))]) / 3.0;
  const int lo = int(std::ceil(std::max(4.0 * in.smoothed_sigma, 0.15 * span) / b));
  const int hi = int(std::floor((span - std::max(4.0 * in.smoothed_sigma, 0.1 * span)) / b)) - 1;
  if (hi - lo < 2) return out;
  int m = lo;
  for (int k = lo; k <= hi; ++k)
    if (a[size_t(k)] > a[size_t(m)]) m = k;
  if (m == lo || m == hi) return out;  // a slope, no interior maximum
  double left = a[size_t(m)], right = a[size_t(m)];
  for (int k = lo; k < m; ++k) left = std::min(left, a[size_t(k)]);
  for (int k = m + 1; k <= hi; ++k) right = std::min(right, a[size_t(k)]);
  const double floor = std::max({left, right, 1.0});
  out.level = V + (m + 0.5) * b;
  out.prominence = a[size_t(m)] / floor;
  out.found = out.prominence >= min_prominence;
  return out;
}

int64_t grain_levels_reach(const GrainLevelsOptions& opt) {
  return int64_t(gaussian_kernel(opt.smoothing_sigma_vox).size() / 2) + opt.reach_vox;
}

Volume<uint16_t> normalise_grain_levels(const Volume<uint16_t>& grey, const GrainLevelsInput& in,
                                        const GrainLevelsOptions& opt, GrainLevelsResult* result, int64_t count_z0,
                                        int64_t count_z1) {
  if (!(in.solid_level > in.void_level) || !(in.smoothed_sigma > 0) || !std::isfinite(in.solid_level))
    throw UsageError("segment: grain levels need the void's grey below the solid's and a smoothed noise sigma > 0");
  if (!(opt.smoothing_sigma_vox > 0) || opt.reach_vox < 1 || !(opt.max_gain >= 1) || !(opt.smooth_from_gain > 1))
    throw UsageError("segment: grain levels: smoothing > 0, reach >= 1 voxel, max gain >= 1, smooth-from gain > 1");
  const std::vector<float> w = gaussian_kernel(opt.smoothing_sigma_vox);
  const int rg = int(w.size() / 2);
  Volume<uint16_t> S(grey.shape(), grey.geometry());
  separable(grey, S, rg, GaussFold{w});
  Volume<uint16_t> M(grey.shape(), grey.geometry());
  separable(S, M, opt.reach_vox, MaxFold{});

  // Single precision: the grey has 16 bits, the gain 2-3 digits.
  const float V = float(in.void_level), P = float(in.solid_level);
  const float floor = float(opt.min_excess_sigmas * in.smoothed_sigma);
  const float inv_span = float(1.0 / (opt.smooth_from_gain - 1.0)), gmax = float(opt.max_gain);
  const uint16_t* G = grey.data();
  const uint16_t* Sd = S.data();
  uint16_t* Md = M.data();  // becomes grey'
  const int64_t n = grey.size(), sl = grey.shape().slice_voxels();
  const int64_t c0 = std::clamp<int64_t>(count_z0, 0, grey.shape().nz) * sl;
  const int64_t c1 = (count_z1 < 0 ? grey.shape().nz : std::clamp<int64_t>(count_z1, 0, grey.shape().nz)) * sl;
  int64_t raised = 0, smoothed = 0;
#pragma omp parallel for schedule(static) reduction(+ : raised, smoothed)
  for (int64_t i = 0; i < n; ++i) {
    const float m = float(Md[i]), ex = m - V;
    if (!(ex >= floor) || m >= P) {
      Md[i] = G[i];
      continue;
    }
    const float gain = std::min(gmax, (P - V) / ex);
    const float wt = std::clamp((gain - 1.0f) * inv_span, 0.0f, 1.0f);
    const bool counted = i >= c0 && i < c1;
    raised += counted;
    smoothed += counted && wt >= 1.0f;
    Md[i] = to_u16(V + gain * ((1.0f - wt) * (float(G[i]) - V) + wt * (float(Sd[i]) - V)));
  }
  if (result) {
    result->used = true;
    result->levels = in;
    result->voxels_raised = raised;
    result->voxels_from_smoothed = smoothed;
  }
  return M;
}

}  // namespace tg

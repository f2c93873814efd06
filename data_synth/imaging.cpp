#include "data_synth/imaging.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/errors.hpp"
#include "data_synth/rng.hpp"

namespace tg::synth {

namespace {

// Convolve n values spaced by `stride` with kernel w (radius r), borders replicated.
void blur_line(float* p, int64_t n, int64_t stride, const std::vector<double>& w, std::vector<double>& buf) {
  const int64_t r = static_cast<int64_t>(w.size()) - 1;
  buf.resize(static_cast<size_t>(n));
  for (int64_t q = 0; q < n; ++q) buf[q] = p[q * stride];
  for (int64_t q = 0; q < n; ++q) {
    double s = w[0] * buf[q];
    for (int64_t t = 1; t <= r; ++t)
      s += w[t] * (buf[std::max<int64_t>(q - t, 0)] + buf[std::min<int64_t>(q + t, n - 1)]);
    p[q * stride] = static_cast<float>(s);
  }
}

// Poisson(λ) from the counter stream of one voxel: inversion for λ <= 50, normal approximation above.
double poisson(double lambda, uint64_t seed, uint64_t key) {
  if (lambda <= 0) return 0;
  if (lambda > 50) return std::max(0.0, std::round(lambda + std::sqrt(lambda) * normal01(seed, key, 10)));
  // Inversion by sequential search (about λ steps).
  const double u = uniform01(seed, key, 12);
  double p = std::exp(-lambda), cdf = p;
  int64_t k = 0;
  while (u > cdf && k < 100000) {
    ++k;
    p *= lambda / static_cast<double>(k);
    cdf += p;
  }
  return static_cast<double>(k);
}

}  // namespace

void gaussian_blur(Volume<float>& v, double sigma) {
  if (!(sigma >= 0)) throw InputError("psf sigma must be >= 0");
  if (sigma == 0 || v.empty()) return;
  const int r = std::max(1, static_cast<int>(std::ceil(4 * sigma)));
  std::vector<double> w(static_cast<size_t>(r) + 1);
  double sum = 0;
  for (int t = 0; t <= r; ++t) {
    w[t] = std::exp(-0.5 * t * t / (sigma * sigma));
    sum += t == 0 ? w[t] : 2 * w[t];
  }
  for (double& x : w) x /= sum;
  const Shape s = v.shape();
  float* d = v.data();
  const int64_t sv = s.slice_voxels();
  // x lines, then y lines, then z lines; each line is independent.
#pragma omp parallel
  {
    std::vector<double> buf;
#pragma omp for schedule(static)
    for (int64_t q = 0; q < s.nz * s.ny; ++q) blur_line(d + q * s.nx, s.nx, 1, w, buf);
#pragma omp for schedule(static)
    for (int64_t q = 0; q < s.nz * s.nx; ++q) blur_line(d + (q / s.nx) * sv + q % s.nx, s.ny, s.nx, w, buf);
#pragma omp for schedule(static)
    for (int64_t q = 0; q < sv; ++q) blur_line(d + q, s.nz, sv, w, buf);
  }
}

void apply_imaging(Volume<float>& v, const ImagingOptions& o) {
  if (!(o.noise_sigma >= 0) || !(o.poisson_counts_per_grey >= 0) || !(o.cupping >= 0 && o.cupping < 1) ||
      o.rings < 0 || !(o.void_grey >= 0) || !(o.solid_grey >= 0))
    throw InputError("imaging: grey levels, noise and cupping must be non-negative (cupping < 1)");
  const Shape s = v.shape();
  const int64_t n = v.size();
  float* d = v.data();
#pragma omp parallel for schedule(static)
  for (int64_t q = 0; q < n; ++q) d[q] = static_cast<float>(o.void_grey + (o.solid_grey - o.void_grey) * d[q]);
  gaussian_blur(v, o.psf_sigma);
  // Radial profile per slice position (same for every slice): cupping and rings.
  const double cy = 0.5 * s.ny, cx = 0.5 * s.nx, redge = 0.5 * std::min(s.ny, s.nx);
  std::vector<double> ring_r(static_cast<size_t>(o.rings)), ring_a(static_cast<size_t>(o.rings));
  for (int q = 0; q < o.rings; ++q) {
    ring_r[q] = redge * uniform01(o.seed, 0x7149, 2 * q);
    ring_a[q] = (uniform01(o.seed, 0x7149, 2 * q + 1) < 0.5 ? -1 : 1) * o.ring_amplitude;
  }
  std::vector<float> gain(static_cast<size_t>(s.slice_voxels()), 1.0f), offset(gain.size(), 0.0f);
  if (o.cupping > 0 || o.rings > 0)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        const double r = std::hypot(j + 0.5 - cy, i + 0.5 - cx), t = std::min(1.0, r / redge);
        gain[j * s.nx + i] = static_cast<float>(1 - o.cupping * (1 - t * t));
        double off = 0;
        for (int q = 0; q < o.rings; ++q)
          if (std::abs(r - ring_r[q]) < 0.5) off += ring_a[q];
        offset[j * s.nx + i] = static_cast<float>(off);
      }
  const int64_t sv = s.slice_voxels();
  const bool noisy = o.noise_sigma > 0 || o.poisson_counts_per_grey > 0;
#pragma omp parallel for schedule(static)
  for (int64_t q = 0; q < n; ++q) {
    double g = d[q] * gain[q % sv] + offset[q % sv];
    if (noisy) {
      const uint64_t key = static_cast<uint64_t>(q);
      if (o.poisson_counts_per_grey > 0) {
        const double k = o.poisson_counts_per_grey;
        g = poisson(std::max(0.0, g) * k, o.seed, key) / k;
      }
      if (o.noise_sigma > 0) g += o.noise_sigma * normal01(o.seed, key, 0);
    }
    d[q] = static_cast<float>(g);
  }
}

U16Result to_u16(const Volume<float>& g) {
  U16Result r;
  r.volume = Volume<uint16_t>(g.shape(), g.geometry());
  const int64_t n = g.size();
  int64_t lo = 0, hi = 0;
  const float* s = g.data();
  uint16_t* d = r.volume.data();
#pragma omp parallel for schedule(static) reduction(+ : lo, hi)
  for (int64_t q = 0; q < n; ++q) {
    const double v = std::round(static_cast<double>(s[q]));
    if (!(v > 0)) {  // NaN maps to 0 too
      d[q] = 0;
      lo += v < 0;
    } else if (v > 65535) {
      d[q] = 65535;
      ++hi;
    } else {
      d[q] = static_cast<uint16_t>(v);
    }
  }
  r.saturated_low = lo;
  r.saturated_high = hi;
  return r;
}

}  // namespace tg::synth

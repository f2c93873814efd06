#include "segmentation/noise_specks.hpp"

#include <algorithm>
#include <cmath>
#include <omp.h>
#include <stdexcept>
#include <vector>

namespace tg {

Excess noise_excess_above(double z_t) {
  // Beyond ~30 sigmas Q underflows; the excess tends to 1 / z_t there.
  const double z = std::clamp(z_t, -8.0, 30.0);
  const double q = 0.5 * std::erfc(z / std::sqrt(2.0));
  const double phi = std::exp(-0.5 * z * z) / std::sqrt(2.0 * M_PI);
  const double lambda = phi / q;
  Excess e;
  e.mean = lambda - z;
  e.sigma = std::sqrt(std::max(1e-12, 1.0 + z * lambda - lambda * lambda));
  return e;
}

namespace {

// Gaussian weights, sigma 1 voxel, to 3 sigmas, normalised (the split
// repair's smoothing, split_labels.hpp).
std::array<double, 7> unit_gaussian() {
  std::array<double, 7> w{};
  double s = 0;
  for (int k = -3; k <= 3; ++k) s += w[size_t(k + 3)] = std::exp(-0.5 * k * k);
  for (auto& x : w) x /= s;
  return w;
}

// The grey code smoothed at voxel (k, j, i), the volume's faces repeated.
double smoothed_at(const Volume<uint8_t>& g, const std::array<double, 7>& w, int64_t k, int64_t j, int64_t i) {
  const Shape s = g.shape();
  double acc = 0;
  for (int a = -3; a <= 3; ++a) {
    const int64_t kk = std::clamp<int64_t>(k + a, 0, s.nz - 1);
    for (int b = -3; b <= 3; ++b) {
      const int64_t jj = std::clamp<int64_t>(j + b, 0, s.ny - 1);
      const uint8_t* row = g.data() + (kk * s.ny + jj) * s.nx;
      double line = 0;
      for (int c = -3; c <= 3; ++c) line += w[size_t(c + 3)] * row[std::clamp<int64_t>(i + c, 0, s.nx - 1)];
      acc += w[size_t(a + 3)] * w[size_t(b + 3)] * line;
    }
  }
  return acc;
}

}  // namespace

SpeckResult find_noise_specks(const Volume<uint32_t>& labels, uint32_t count, const Volume<uint8_t>& grey_code,
                              const SpeckTest& test) {
  if (!(labels.shape() == grey_code.shape())) throw std::logic_error("find_noise_specks: labels and grey differ in shape");
  SpeckResult r;
  if (count == 0 || !(test.sigma > 0)) return r;
  r.used = true;
  const Excess e = noise_excess_above((test.threshold - test.void_level) / test.sigma);
  r.mu0 = e.mean, r.s0 = e.sigma;
  // Per label: voxels and the sum of their codes (integers: exact, in any order).
  const int nt = omp_get_max_threads();
  std::vector<std::vector<int64_t>> part_n(static_cast<size_t>(nt)), part_sum(static_cast<size_t>(nt));
  const uint32_t* L = labels.data();
  const uint8_t* G = grey_code.data();
  const Shape s = labels.shape();
  const int64_t rows = s.nz * s.ny;
#pragma omp parallel num_threads(nt)
  {
    auto& pn = part_n[size_t(omp_get_thread_num())];
    auto& ps = part_sum[size_t(omp_get_thread_num())];
    pn.assign(size_t(count) + 1, 0);
    ps.assign(size_t(count) + 1, 0);
#pragma omp for schedule(static)
    for (int64_t row = 0; row < rows; ++row) {
      const uint32_t* lr = L + row * s.nx;
      const uint8_t* gr = G + row * s.nx;
      for (int64_t i = 0; i < s.nx;) {  // by runs of one label
        const uint32_t l = lr[i];
        int64_t end = i + 1;
        while (end < s.nx && lr[end] == l) ++end;
        if (l != 0 && l <= count) {
          int64_t sum = 0;
          for (int64_t k = i; k < end; ++k) sum += gr[k];
          pn[l] += end - i;
          ps[l] += sum;
        }
        i = end;
      }
    }
  }
  // Candidates: labels whose mean is noise-like (first condition).
  std::vector<int64_t> size(size_t(count) + 1, 0);
  std::vector<int32_t> slot(size_t(count) + 1, -1);  // candidate number, or -1
  std::vector<uint32_t> cand;
  for (uint32_t l = 1; l <= count; ++l) {
    int64_t n = 0, sum = 0;
    for (int t = 0; t < nt; ++t) n += part_n[size_t(t)][l], sum += part_sum[size_t(t)][l];
    size[l] = n;
    if (n == 0) continue;
    ++r.tested;
    const double m = (double(sum) / double(n) - test.threshold) / test.sigma;
    const double z = (m - e.mean) / (e.sigma / std::sqrt(double(n)));
    if (z < test.z_crit && n <= test.max_candidate_vox) {
      slot[l] = int32_t(cand.size());
      cand.push_back(l);
    }
  }
  r.keep.resize(size_t(count) + 1);
  for (uint32_t l = 0; l <= count; ++l) r.keep[l] = l;
  if (cand.empty()) return r;
  // Their voxels (raster order), then the second condition: no voxel whose
  // smoothed grey reaches the threshold (a core).
  std::vector<std::vector<int64_t>> vox(cand.size());
  for (int64_t q = 0; q < labels.size(); ++q)
    if (L[q] && L[q] <= count && slot[L[q]] >= 0) vox[size_t(slot[L[q]])].push_back(q);
  const std::array<double, 7> w = unit_gaussian();
  std::vector<uint8_t> noise(cand.size(), 0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t c = 0; c < int64_t(cand.size()); ++c) {
    bool core = false;
    for (const int64_t q : vox[size_t(c)]) {
      const int64_t k = q / (s.ny * s.nx), j = (q / s.nx) % s.ny, i = q % s.nx;
      if (smoothed_at(grey_code, w, k, j, i) >= test.threshold) {
        core = true;
        break;
      }
    }
    noise[size_t(c)] = !core;
  }
  for (size_t c = 0; c < cand.size(); ++c)
    if (noise[c]) {
      r.keep[cand[c]] = 0;
      ++r.dropped;
      r.dropped_voxels += size[cand[c]];
    }
  return r;
}

}  // namespace tg

#include "dem/neighbor_grid.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "core/errors.hpp"

namespace tg::dem {

namespace {
inline bool in_range(const Particles& p, int64_t a, int64_t b, double skin) {
  const double dx = p.x[a] - p.x[b], dy = p.y[a] - p.y[b], dz = p.z[a] - p.z[b];
  const double c = p.r[a] + p.r[b] + skin;
  return dx * dx + dy * dy + dz * dz < c * c;
}
}  // namespace

PairListCSR build_pairs_brute_force(const Particles& p, double skin) {
  const int64_t n = p.size();
  PairListCSR out;
  out.offsets.assign(static_cast<size_t>(n + 1), 0);
  for (int64_t i = 0; i < n; ++i) {
    for (int64_t k = i + 1; k < n; ++k)
      if (in_range(p, i, k, skin)) out.j.push_back(k);
    out.offsets[static_cast<size_t>(i + 1)] = static_cast<int64_t>(out.j.size());
  }
  return out;
}

PairListCSR build_pairs_grid(const Particles& p, double skin) {
  const int64_t n = p.size();
  PairListCSR out;
  out.offsets.assign(static_cast<size_t>(n + 1), 0);
  if (n == 0) return out;
  double lo[3] = {p.x[0], p.y[0], p.z[0]}, hi[3] = {lo[0], lo[1], lo[2]};
  double rmax = 0;
  for (int64_t i = 0; i < n; ++i) {
    const double c[3] = {p.x[i], p.y[i], p.z[i]};
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], c[d]);
      hi[d] = std::max(hi[d], c[d]);
    }
    rmax = std::max(rmax, p.r[i]);
    if (!std::isfinite(c[0] + c[1] + c[2] + p.r[i]))
      throw InputError("neighbour search: sphere " + std::to_string(i) + " has a non-finite position or radius");
  }
  double h = 2 * rmax + skin;
  if (!(h > 0)) h = 1e-12;
  int64_t dims[3];
  // Grow the cell until the grid has at most ~8n + 64 cells (far-flung spheres).
  for (;;) {
    int64_t total = 1;
    for (int d = 0; d < 3; ++d) {
      dims[d] = static_cast<int64_t>((hi[d] - lo[d]) / h) + 1;
      total *= dims[d];
    }
    if (total <= 8 * n + 64) break;
    h *= 1.5;
  }
  assert(h >= 2 * rmax + skin);  // every pair in range lies in adjacent cells
  const int64_t ncell = dims[0] * dims[1] * dims[2];
  std::vector<int64_t> cell_of(static_cast<size_t>(n));
  std::vector<int64_t> cell_start(static_cast<size_t>(ncell + 1), 0);
  auto coord = [&](double v, int d) {
    return std::min<int64_t>(dims[d] - 1, static_cast<int64_t>((v - lo[d]) / h));
  };
  for (int64_t i = 0; i < n; ++i) {
    const int64_t c = (coord(p.z[i], 2) * dims[1] + coord(p.y[i], 1)) * dims[0] + coord(p.x[i], 0);
    cell_of[static_cast<size_t>(i)] = c;
    ++cell_start[static_cast<size_t>(c + 1)];
  }
  for (int64_t c = 0; c < ncell; ++c) cell_start[static_cast<size_t>(c + 1)] += cell_start[static_cast<size_t>(c)];
  std::vector<int64_t> cell_ids(static_cast<size_t>(n));
  {
    std::vector<int64_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (int64_t i = 0; i < n; ++i) cell_ids[static_cast<size_t>(fill[static_cast<size_t>(cell_of[static_cast<size_t>(i)])]++)] = i;
  }

  // Two passes (count, then fill) so the CSR is built in parallel without locks.
  auto scan = [&](int64_t i, auto&& emit) {
    const int64_t c = cell_of[static_cast<size_t>(i)];
    const int64_t cx = c % dims[0], cy = (c / dims[0]) % dims[1], cz = c / (dims[0] * dims[1]);
    for (int64_t z = std::max<int64_t>(0, cz - 1); z <= std::min(dims[2] - 1, cz + 1); ++z)
      for (int64_t y = std::max<int64_t>(0, cy - 1); y <= std::min(dims[1] - 1, cy + 1); ++y)
        for (int64_t x = std::max<int64_t>(0, cx - 1); x <= std::min(dims[0] - 1, cx + 1); ++x) {
          const int64_t cc = (z * dims[1] + y) * dims[0] + x;
          for (int64_t s = cell_start[static_cast<size_t>(cc)]; s < cell_start[static_cast<size_t>(cc + 1)]; ++s) {
            const int64_t k = cell_ids[static_cast<size_t>(s)];
            if (k > i && in_range(p, i, k, skin)) emit(k);
          }
        }
  };
  std::vector<int64_t> count(static_cast<size_t>(n), 0);
#pragma omp parallel for schedule(static) if (n >= 2048)
  for (int64_t i = 0; i < n; ++i) {
    int64_t c = 0;
    scan(i, [&](int64_t) { ++c; });
    count[static_cast<size_t>(i)] = c;
  }
  for (int64_t i = 0; i < n; ++i) out.offsets[static_cast<size_t>(i + 1)] = out.offsets[static_cast<size_t>(i)] + count[static_cast<size_t>(i)];
  out.j.resize(static_cast<size_t>(out.offsets[static_cast<size_t>(n)]));
#pragma omp parallel for schedule(static) if (n >= 2048)
  for (int64_t i = 0; i < n; ++i) {
    int64_t w = out.offsets[static_cast<size_t>(i)];
    scan(i, [&](int64_t k) { out.j[static_cast<size_t>(w++)] = k; });
    std::sort(out.j.begin() + out.offsets[static_cast<size_t>(i)], out.j.begin() + w);
  }
  return out;
}

}  // namespace tg::dem

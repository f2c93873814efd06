#include "segmentation/merge_labels.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include <omp.h>

#include "core/errors.hpp"
#include "segmentation/neighbourhood.hpp"

namespace tg {
namespace {

// An interface's size in units (line voxels or faces): all of it, and its
// bright part (grey evidence).
struct Area {
  int64_t all = 0, bright = 0, share = 0;  // share: bright past the pair's own level (MergeOptions::grey)
  Area& operator+=(const Area& o) {
    all += o.all, bright += o.bright, share += o.share;
    return *this;
  }
};

uint64_t pair_key(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (uint64_t(a) << 32) | b;
}

// Distinct nonzero labels among the 26 neighbours of voxel (k, j, i) at idx
// (up to 3 kept: enough to tell "one", "two" and "more").
int neighbour_labels(const Volume<uint32_t>& lab, const seg::Neighbourhood& nb, int64_t k, int64_t j, int64_t i,
                     int64_t idx, uint32_t out[3]) {
  const Shape s = lab.shape();
  const bool in = seg::interior(s, k, j, i);
  int n = 0;
  for (int t = 0; t < nb.count; ++t) {
    if (!in) {
      const seg::Step st = nb.step[size_t(t)];
      if (!s.contains(k + st.dz, j + st.dy, i + st.dx)) continue;
    }
    const uint32_t l = lab[idx + nb.offset[size_t(t)]];
    if (l == 0 || std::find(out, out + n, l) != out + n) continue;
    out[n++] = l;
    if (n == 3) break;
  }
  return n;
}

// Each label's voxels above `floor` and the sum of their greys (integers
// per thread, added up: the same on any thread count).
struct GreySums {
  std::vector<int64_t> sum, count;
  // The mean grey above `floor` of labels a and b together (`floor` where
  // they have no such voxel).
  double level(uint32_t a, uint32_t b, uint8_t floor) const {
    const int64_t c = count[a] + count[b];
    return c ? double(sum[a] + sum[b]) / double(c) : double(floor);
  }
};
GreySums grey_sums(const Volume<uint32_t>& labels, const Volume<uint8_t>& grey, uint32_t maxl, uint8_t floor) {
  if (grey.shape() != labels.shape()) throw UsageError("merge: labels and grey differ in shape");
  const int64_t n = labels.size();
  const uint32_t* L = labels.data();
  const uint8_t* G = grey.data();
  GreySums r{std::vector<int64_t>(size_t(maxl) + 1, 0), std::vector<int64_t>(size_t(maxl) + 1, 0)};
#pragma omp parallel if (int64_t(maxl) <= n / 16)
  {
    std::vector<int64_t> my_sum(r.sum.size(), 0), my_count(r.sum.size(), 0);
#pragma omp for schedule(static)
    for (int64_t i = 0; i < n; ++i)
      if (L[i] && G[i] > floor) my_sum[L[i]] += G[i], ++my_count[L[i]];
#pragma omp critical
    for (size_t l = 0; l < r.sum.size(); ++l) r.sum[l] += my_sum[l], r.count[l] += my_count[l];
  }
  return r;
}

// Unions of labels 0..n-1 (the smaller root wins: merged labels keep the
// smallest number of their group), and what both merges do with them.
struct Unions {
  std::vector<uint32_t> parent;
  explicit Unions(size_t n) : parent(n) {
    for (size_t l = 0; l < n; ++l) parent[l] = uint32_t(l);
  }
  uint32_t find(uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  bool join(uint32_t a, uint32_t b) {  // false when already one group
    const uint32_t ra = find(a), rb = find(b);
    if (ra == rb) return false;
    parent[std::max(ra, rb)] = std::min(ra, rb);
    return true;
  }
  // Each label's root; the line voxels listed between two labels of one
  // group join it (decided from the labels as they were before any joined).
  std::vector<uint32_t> roots_joining_lines(uint32_t* L,
                                            const std::vector<std::vector<std::pair<int64_t, uint64_t>>>& lines) {
    std::vector<uint32_t> root(parent.size());
    for (size_t l = 0; l < root.size(); ++l) root[l] = find(uint32_t(l));
    for (const auto& list : lines)
      for (const auto& [idx, key] : list) {
        const uint32_t r = root[uint32_t(key >> 32)];
        if (root[uint32_t(key & 0xffffffffu)] == r) L[idx] = r;
      }
    return root;
  }
};

}  // namespace

MergeResult merge_oversegmented(Volume<uint32_t>& labels, const Volume<uint8_t>& solid, const MergeOptions& opt) {
  if (labels.shape() != solid.shape()) throw UsageError("merge: labels and mask differ in shape");
  if (!(opt.ratio >= 0) || !std::isfinite(opt.ratio)) throw UsageError("merge: ratio must be finite and >= 0");
  const Shape s = labels.shape();
  const int64_t n = labels.size();
  uint32_t* L = labels.data();
  const uint8_t* m = solid.data();
  const uint8_t bright = std::max<uint8_t>(opt.bright_level, 1);
  if (opt.grey && opt.grey->shape() != s) throw UsageError("merge: labels and grey differ in shape");
  const uint8_t* G = opt.grey ? opt.grey->data() : nullptr;
  if (G && !(opt.grey_fraction >= 0 && opt.grey_fraction <= 1))
    throw UsageError("merge: grey_fraction must lie in 0..1");
  uint32_t maxl = 0;
#pragma omp parallel for schedule(static) reduction(max : maxl)
  for (int64_t i = 0; i < n; ++i) maxl = std::max(maxl, L[i]);
  std::vector<int64_t> vol(size_t(maxl) + 1, 0);
  const GreySums sums = G ? grey_sums(labels, *opt.grey, maxl, opt.grey_floor) : GreySums{};
  // The grey a voxel of the interface of a and b needs to count bright for
  // the share: grey_fraction of the way to the pair's level.
  auto share_level = [&](uint64_t key) {
    const double level = sums.level(uint32_t(key >> 32), uint32_t(key & 0xffffffffu), opt.grey_floor);
    return double(opt.grey_floor) + opt.grey_fraction * (level - double(opt.grey_floor));
  };
  // 0: dim; 1: graded bright; 2: bright for the share too (at or above
  // `share`, or brightened by the pore filling).
  auto brightness = [&](int64_t idx, double share) -> int {
    if (m[idx] < bright) return 0;
    return !G || G[idx] <= opt.grey_filled || double(G[idx]) >= share ? 2 : 1;
  };

  // Volumes, and interfaces: line voxels between exactly two labels, and
  // direct faces. Slices in parallel, each thread with its own tables,
  // summed at the end (integer counts: the sums do not depend on the order;
  // the pairs are visited in key order below).
  const seg::Neighbourhood nb(s, 26);
  std::unordered_map<uint64_t, Area> iface;
  // Line voxels between exactly two labels, per thread in index order:
  // those between two labels that merge join them below, without a second
  // look at their neighbours.
  const int nthreads = omp_get_max_threads();
  std::vector<std::vector<std::pair<int64_t, uint64_t>>> two{static_cast<size_t>(nthreads)};
  const bool parallel = int64_t(maxl) <= n / 16;
#pragma omp parallel num_threads(nthreads) if (parallel)
  {
    std::vector<int64_t> my_vol(vol.size(), 0);
    std::unordered_map<uint64_t, Area> my_iface;
    auto& my_two = two[size_t(omp_get_thread_num())];
    // Neighbouring interface voxels mostly share their pair: counts go to
    // the map when the pair changes, not one lookup a voxel.
    uint64_t last_key = 0;
    Area pending;
    auto count_pair = [&](uint64_t key, int level) {  // level as brightness()
      if (key != last_key) {
        if (pending.all) my_iface[last_key] += pending;
        last_key = key;
        pending = {};
      }
      ++pending.all;
      pending.bright += level >= 1;
      pending.share += level == 2;
    };
    // Row by row, in runs of one label: a run adds its length to the
    // label's volume; its voxels are looked at one by one only where that
    // can count (line voxels; a y or z neighbour of another label, which
    // watershed lines leave none of), found by one comparison a voxel.
    const int64_t sy = s.nx, sz = s.slice_voxels();
#pragma omp for schedule(static)
    for (int64_t k = 0; k < s.nz; ++k)
      for (int64_t j = 0; j < s.ny; ++j) {
        const int64_t row = s.index(k, j, 0);
        const uint32_t* up = j + 1 < s.ny ? L + row + sy : nullptr;
        const uint32_t* back = k + 1 < s.nz ? L + row + sz : nullptr;
        for (int64_t i0 = 0; i0 < s.nx;) {
          const uint32_t a = L[row + i0];
          int64_t i1 = i0 + 1;
          while (i1 < s.nx && L[row + i1] == a) ++i1;
          my_vol[a] += i1 - i0;
          if (a == 0) {
            for (int64_t i = i0; i < i1; ++i) {
              const int64_t idx = row + i;
              if (!m[idx]) continue;
              uint32_t ls[3];
              if (neighbour_labels(labels, nb, k, j, i, idx, ls) == 2) {
                const uint64_t key = pair_key(ls[0], ls[1]);
                count_pair(key, brightness(idx, G ? share_level(key) : 0.0));
                my_two.emplace_back(idx, key);
              }
            }
          } else {
            // Forward faces, in the order the voxel loop counted them: x
            // (only the run's last voxel can meet another label), y, z.
            for (int64_t i = i0; i < i1; ++i) {
              const uint32_t by = up ? up[i] : 0, bz = back ? back[i] : 0;
              const bool x_other = i + 1 == i1 && i1 < s.nx && L[row + i1] != 0;
              if (!x_other && (by == 0 || by == a) && (bz == 0 || bz == a)) continue;
              // A face is as bright as the dimmer of its voxels.
              const int64_t idx = row + i;
              auto face = [&](uint32_t b, int64_t other) {
                const uint64_t key = pair_key(a, b);
                const double share = G ? share_level(key) : 0.0;
                count_pair(key, std::min(brightness(idx, share), brightness(other, share)));
              };
              if (x_other) face(L[row + i1], idx + 1);
              if (by != 0 && by != a) face(by, idx + sy);
              if (bz != 0 && bz != a) face(bz, idx + sz);
            }
          }
          i0 = i1;
        }
      }
    if (pending.all) my_iface[last_key] += pending;
#pragma omp critical
    {
      for (size_t l = 0; l < vol.size(); ++l) vol[l] += my_vol[l];
      for (const auto& [key, area] : my_iface) iface[key] += area;
    }
  }

  MergeResult res;
  res.touching_pairs = int64_t(iface.size());
  Unions unions(size_t(maxl) + 1);
  // Each label's best partner: among the pairs that pass the criterion with
  // it as the smaller label (equal volumes: the higher number is the
  // smaller), the one with the largest interface (ties: the lowest number,
  // the first in key order).
  const std::map<uint64_t, Area> ordered(iface.begin(), iface.end());  // deterministic order
  std::vector<uint32_t> best(size_t(maxl) + 1, 0);
  std::vector<int64_t> best_area(size_t(maxl) + 1, 0);
  for (const auto& [key, area] : ordered) {
    uint32_t a = uint32_t(key >> 32), b = uint32_t(key & 0xffffffffu);  // a < b
    if (vol[a] < vol[b] || (vol[a] == vol[b] && a > b)) std::swap(a, b);
    const uint32_t small = b, large = a;
    const double r = std::cbrt(3.0 * double(vol[small]) / (4.0 * std::numbers::pi));
    if (double(area.bright) < opt.ratio * std::numbers::pi * r * r) continue;
    if (double(area.share) < opt.min_bright_share * double(area.all)) continue;
    ++res.candidates;
    if (area.bright > best_area[small]) best_area[small] = area.bright, best[small] = large;
  }
  for (uint32_t l = 1; l <= maxl; ++l) {
    if (best[l] == 0) continue;
    res.merges += unions.join(l, best[l]);
  }
  if (res.merges == 0) return res;

  // Line voxels whose neighbours all belong to one merged label join it.
  std::vector<uint32_t> root = unions.roots_joining_lines(L, two);
  if (!opt.apply) {
    res.root = std::move(root);
    return res;
  }
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) L[i] = root[L[i]];
  return res;
}

WallMergeResult merge_thin_walls(Volume<uint32_t>& labels, const Volume<uint8_t>& grey,
                                 const std::vector<uint8_t>& thin, const std::vector<Box>& thin_boxes,
                                 const WallMergeOptions& opt) {
  if (!(labels.shape() == grey.shape())) throw std::logic_error("merge_thin_walls: labels and grey differ in shape");
  WallMergeResult res;
  for (const uint8_t t : thin) res.thin_labels += t;
  if (res.thin_labels < 2) return res;
  const Shape s = labels.shape();
  uint32_t* L = labels.data();
  const uint8_t* G = grey.data();
  const size_t nl = thin.size();
  auto is_thin = [&](uint32_t l) { return l != 0 && size_t(l) < nl && thin[l]; };
  // Each row's stretch of x that the thin labels' boxes, grown by one, cover.
  std::vector<int64_t> x_lo(size_t(s.nz * s.ny), s.nx), x_hi(size_t(s.nz * s.ny), -1);
  for (const Box& b : thin_boxes)
    for (int64_t k = std::max<int64_t>(b.z0 - 1, 0); k <= std::min(b.z0 + b.size.nz, s.nz - 1); ++k)
      for (int64_t j = std::max<int64_t>(b.y0 - 1, 0); j <= std::min(b.y0 + b.size.ny, s.ny - 1); ++j) {
        const size_t row = size_t(k * s.ny + j);
        x_lo[row] = std::min(x_lo[row], std::max<int64_t>(b.x0 - 1, 0));
        x_hi[row] = std::max(x_hi[row], std::min(b.x0 + b.size.nx, s.nx - 1));
      }
  const seg::Neighbourhood nb(s, 26);
  const int nthreads = omp_get_max_threads();
  std::unordered_map<uint64_t, Area> iface;
  std::vector<std::vector<std::pair<int64_t, uint64_t>>> two{static_cast<size_t>(nthreads)};
#pragma omp parallel num_threads(nthreads)
  {
    std::unordered_map<uint64_t, Area> mine;
    auto& my_two = two[size_t(omp_get_thread_num())];
    const int64_t sy = s.nx, sz = s.slice_voxels();
#pragma omp for schedule(static)
    for (int64_t k = 0; k < s.nz; ++k)
      for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = x_lo[size_t(k * s.ny + j)]; i <= x_hi[size_t(k * s.ny + j)]; ++i) {
          const int64_t idx = s.index(k, j, i);
          const uint32_t a = L[idx];
          if (a == 0) {
            if (G[idx] < opt.floor) continue;
            uint32_t ls[3];
            if (neighbour_labels(labels, nb, k, j, i, idx, ls) != 2 || !is_thin(ls[0]) || !is_thin(ls[1])) continue;
            const uint64_t key = pair_key(ls[0], ls[1]);
            Area& ar = mine[key];
            ++ar.all;
            ar.bright += G[idx] >= opt.bright;
            my_two.emplace_back(idx, key);
          } else if (is_thin(a)) {
            // Forward faces to another thin label (a face is bright when both voxels are).
            const int64_t fwd[3] = {i + 1 < s.nx ? idx + 1 : -1, j + 1 < s.ny ? idx + sy : -1,
                                    k + 1 < s.nz ? idx + sz : -1};
            for (const int64_t w : fwd) {
              if (w < 0 || L[w] == a || !is_thin(L[w])) continue;
              Area& ar = mine[pair_key(a, L[w])];
              ++ar.all;
              ar.bright += G[idx] >= opt.bright && G[w] >= opt.bright;
            }
          }
        }
#pragma omp critical
    for (const auto& [key, area] : mine) iface[key] += area;
  }
  res.touching_pairs = int64_t(iface.size());
  Unions unions(nl);
  const std::map<uint64_t, Area> ordered(iface.begin(), iface.end());  // deterministic order
  for (const auto& [key, area] : ordered) {
    if (area.bright < opt.min_area || double(area.bright) < opt.min_bright_share * double(area.all)) continue;
    res.merges += unions.join(uint32_t(key >> 32), uint32_t(key & 0xffffffffu));
  }
  if (res.merges == 0) return res;
  const std::vector<uint32_t> root = unions.roots_joining_lines(L, two);
  const int64_t n = labels.size();
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
    if (L[i] && size_t(L[i]) < nl) L[i] = root[L[i]];
  return res;
}

}  // namespace tg

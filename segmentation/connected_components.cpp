#include "segmentation/connected_components.hpp"

#include <algorithm>
#include <limits>

#include <omp.h>

#include "core/errors.hpp"
#include "segmentation/neighbourhood.hpp"
#include "segmentation/runs.hpp"

namespace tg {
namespace {

constexpr uint32_t kMaxLabel = std::numeric_limits<uint32_t>::max() - 1;

// Union-find over run ids; the smaller root wins, so a root is the first
// run of its set in raster order. parent[p] <= p always holds (roots only
// ever point down, path halving only shortens), which the flattening uses.
struct Runs {
  std::vector<uint32_t> parent;  // then each run's final label
  uint32_t count = 0;            // components
  uint32_t find(uint32_t a) {
    while (parent[a] != a) {
      parent[a] = parent[parent[a]];  // path halving
      a = parent[a];
    }
    return a;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a < b) parent[b] = a;
    else if (b < a) parent[a] = b;
  }
};

// A backward neighbour row of a run: (dz, dy) and how far past the run's
// ends in x its voxels still touch the run (1 where a diagonal step in x is
// part of the connectivity, else 0).
struct BackRow {
  int dz, dy, reach;
};

std::vector<BackRow> back_rows(int connectivity) {
  if (connectivity == 6) return {{0, -1, 0}, {-1, 0, 0}};
  if (connectivity == 18) return {{0, -1, 1}, {-1, 0, 1}, {-1, -1, 0}, {-1, 1, 0}};
  return {{0, -1, 1}, {-1, -1, 1}, {-1, 0, 1}, {-1, 1, 1}};
}

template <class IsFg>
void label_runs(const Volume<uint8_t>& mask, Volume<uint32_t>& labels, int connectivity, IsFg fg, Runs& runs) {
  const Shape s = mask.shape();
  const int64_t nx = s.nx, rows = s.nz * s.ny;
  const uint8_t* m = mask.data();
  uint32_t* L = labels.data();
  // Each row's first run id: ids are 1.. in raster order.
  const std::vector<int64_t> first = seg::run_offsets(mask, fg);
  const int64_t total = first[size_t(rows)];
  if (total > int64_t(kMaxLabel)) throw ResourceError("connected components: more than 2^32 - 2 runs of voxels");
  // Every voxel gets its run's id (0: background).
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    const uint8_t* row = m + r * nx;
    uint32_t* out = L + r * nx;
    uint32_t id = uint32_t(first[size_t(r)]);
    bool prev = false;
    for (int64_t i = 0; i < nx; ++i) {
      const bool f = fg(row[i]);
      id += f && !prev;
      out[i] = f ? id : 0u;
      prev = f;
    }
  }
  runs.parent.resize(size_t(total) + 1);
#pragma omp parallel for schedule(static)
  for (int64_t p = 0; p <= total; ++p) runs.parent[size_t(p)] = uint32_t(p);

  // Unites each run of row (k, j) with the runs it touches in its backward
  // rows: those of its own slice (dz 0), of the slice below (dz -1), or both.
  const auto back = back_rows(connectivity);
  auto unite_row = [&](int64_t k, int64_t j, bool same_slice, bool below) {
    const uint32_t* row = L + (k * s.ny + j) * nx;
    for (int64_t a = 0; a < nx;) {
      if (!row[a]) {
        ++a;
        continue;
      }
      int64_t b = a + 1;
      while (b < nx && row[b]) ++b;
      const uint32_t u = row[a];
      for (const BackRow& br : back) {
        if (br.dz == 0 ? !same_slice : !below) continue;
        const int64_t kk = k + br.dz, jj = j + br.dy;
        if (kk < 0 || jj < 0 || jj >= s.ny) continue;
        const uint32_t* nrow = L + (kk * s.ny + jj) * nx;
        const int64_t lo = std::max<int64_t>(0, a - br.reach), hi = std::min(nx, b + br.reach);
        uint32_t last = 0;
        for (int64_t i = lo; i < hi; ++i) {
          const uint32_t q = nrow[i];
          if (q && q != last) {
            runs.unite(u, q);
            last = q;
          }
        }
      }
      a = b;
    }
  };
  // Slabs of slices in parallel: within a slab every run touched belongs to
  // the slab, so the slabs' union-finds never share an entry. Each slab's
  // links to the slice below it (the seams) follow, one slab after another.
  // The sets, and so their roots (the first run of each), are the same for
  // any split and any order.
  const int64_t slabs = std::min<int64_t>(s.nz, 4 * int64_t(omp_get_max_threads()));
  auto slab_begin = [&](int64_t p) { return s.nz * p / slabs; };
#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t p = 0; p < slabs; ++p)
    for (int64_t k = slab_begin(p); k < slab_begin(p + 1); ++k)
      for (int64_t j = 0; j < s.ny; ++j) unite_row(k, j, true, k > slab_begin(p));
  for (int64_t p = 1; p < slabs; ++p)
    for (int64_t j = 0; j < s.ny; ++j) unite_row(slab_begin(p), j, false, true);
  // Each run's final number: in increasing order a run's parent is already
  // numbered, and a root takes the next number.
  uint32_t count = 0;
  for (int64_t p = 1; p <= total; ++p) {
    const uint32_t q = runs.parent[size_t(p)];
    runs.parent[size_t(p)] = q == uint32_t(p) ? ++count : runs.parent[q];
  }
  runs.count = count;
}

}  // namespace

ComponentsResult connected_components(const Volume<uint8_t>& mask, Volume<uint32_t>& labels,
                                      const ComponentsOptions& opt) {
  seg::check_connectivity(opt.connectivity);
  if (labels.shape() != mask.shape()) labels = Volume<uint32_t>(mask.shape(), mask.geometry());
  labels.set_geometry(mask.geometry());
  Runs runs;
  if (opt.phase == Phase::nonzero) label_runs(mask, labels, opt.connectivity, [](uint8_t v) { return v != 0; }, runs);
  else label_runs(mask, labels, opt.connectivity, [](uint8_t v) { return v == 0; }, runs);

  const uint32_t count = runs.count;
  const uint32_t* final_of = runs.parent.data();
  std::vector<int64_t> sizes(size_t(count) + 1, 0);
  uint32_t* L = labels.data();
  const int64_t n = labels.size();
  // Per-thread size tables, unless the components are so many (noise) that
  // the tables would weigh more than a sixteenth of the label volume.
#pragma omp parallel if (int64_t(count) <= n / 16)
  {
    std::vector<int64_t> mine(sizes.size(), 0);
#pragma omp for schedule(static)
    for (int64_t i = 0; i < n; ++i) {
      L[i] = final_of[L[i]];
      ++mine[L[i]];
    }
#pragma omp critical
    for (size_t l = 0; l < sizes.size(); ++l) sizes[l] += mine[l];  // integers: any order
  }
  ComponentsResult res;
  res.count = count;
  res.sizes = std::move(sizes);
  res.sizes[0] = 0;
  if (opt.min_size > 1) {
    auto r = relabel_consecutive(labels, opt.min_size);
    res.count = r.count;
    res.dropped = r.dropped;
    res.sizes = std::move(r.sizes);
  }
  return res;
}

RelabelResult relabel_consecutive(Volume<uint32_t>& labels, int64_t min_size, const std::vector<uint32_t>* premap,
                                  const std::vector<uint8_t>* exempt) {
  uint32_t* L = labels.data();
  const int64_t n = labels.size();
  size_t nl = 0;
  if (premap) {
    nl = premap->size();
  } else {
    uint32_t maxl = 0;
#pragma omp parallel for schedule(static) reduction(max : maxl)
    for (int64_t i = 0; i < n; ++i) maxl = std::max(maxl, L[i]);
    nl = size_t(maxl) + 1;
  }
  const uint32_t* pm = premap ? premap->data() : nullptr;
  auto label = [pm, L](int64_t i) { return pm ? pm[L[i]] : L[i]; };
  // Each thread counts its contiguous share of the voxels and lists the
  // labels in the order they first appear in it; the shares taken in order
  // give the raster order of first appearance. Serial when the labels are
  // so many that per-thread tables would outweigh the volume.
  const int threads = int64_t(nl) <= n / 16 ? omp_get_max_threads() : 1;
  std::vector<std::vector<int64_t>> size_of{size_t(threads)};
  std::vector<std::vector<uint32_t>> order{size_t(threads)};
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    std::vector<int64_t>& c = size_of[size_t(t)];
    std::vector<uint32_t>& o = order[size_t(t)];
    c.assign(nl, 0);
    const int64_t lo = n * t / nt, hi = n * (t + 1) / nt;
    for (int64_t i = lo; i < hi; ++i) {
      const uint32_t l = label(i);
      if (c[l]++ == 0) o.push_back(l);
    }
  }
  for (size_t t = 1; t < size_of.size(); ++t)
    for (size_t l = 0; l < nl; ++l) size_of[0][l] += size_of[t][l];
  const std::vector<int64_t>& total = size_of[0];
  // New numbers in raster order of first appearance; 0 = dropped/background.
  constexpr uint32_t kUnset = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> to(nl, kUnset);
  to[0] = 0;
  RelabelResult res;
  res.sizes.push_back(0);
  for (const auto& o : order)
    for (const uint32_t l : o) {
      if (to[l] != kUnset) continue;
      if (total[l] >= min_size || (exempt && l < exempt->size() && (*exempt)[l])) {
        to[l] = ++res.count;
        res.sizes.push_back(total[l]);
      } else {
        to[l] = 0;
        ++res.dropped;
      }
    }
  if (pm)  // counted as premap[l]: label l takes premap[l]'s number
    for (size_t l = 0; l < nl; ++l) to[l] = to[pm[l]];  // in place: a merge's roots map to themselves
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) L[i] = to[L[i]];
  return res;
}

}  // namespace tg

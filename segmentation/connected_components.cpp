#include "segmentation/connected_components.hpp"

#include <algorithm>
#include <limits>

#include "core/errors.hpp"
#include "segmentation/neighbourhood.hpp"

namespace tg {
namespace {

constexpr uint32_t kMaxLabel = std::numeric_limits<uint32_t>::max() - 1;

struct UnionFind {
  std::vector<uint32_t> parent{0};  // parent[0] is the background
  uint32_t make() {
    if (parent.size() > kMaxLabel)
      throw ResourceError("connected components: more than 2^32 - 2 provisional labels");
    parent.push_back(uint32_t(parent.size()));
    return uint32_t(parent.size() - 1);
  }
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

// Pass 1 for one foreground predicate; returns provisional labels.
template <class IsFg>
void first_pass(const Volume<uint8_t>& mask, Volume<uint32_t>& labels, const seg::Neighbourhood& back, IsFg fg,
                UnionFind& uf) {
  const Shape s = mask.shape();
  const uint8_t* m = mask.data();
  uint32_t* L = labels.data();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j) {
      const int64_t row = s.index(k, j, 0);
      for (int64_t i = 0; i < s.nx; ++i) {
        const int64_t idx = row + i;
        if (!fg(m[idx])) {
          L[idx] = 0;
          continue;
        }
        uint32_t lab = 0;
        // Backward neighbours need k-1 >= 0, 0 <= j+dy < ny, 0 <= i+dx < nx.
        const bool inside = k > 0 && j > 0 && i > 0 && j + 1 < s.ny && i + 1 < s.nx;
        for (int n = 0; n < back.count; ++n) {
          if (!inside) {
            const seg::Step d = back.step[size_t(n)];
            if (!s.contains(k + d.dz, j + d.dy, i + d.dx)) continue;
          }
          const uint32_t q = L[idx + back.offset[size_t(n)]];
          if (q == 0) continue;
          if (lab == 0) lab = q;
          else if (q != lab) uf.unite(lab, q);
        }
        L[idx] = lab ? lab : uf.make();
      }
    }
}

}  // namespace

ComponentsResult connected_components(const Volume<uint8_t>& mask, Volume<uint32_t>& labels,
                                      const ComponentsOptions& opt) {
  seg::check_connectivity(opt.connectivity);
  if (labels.shape() != mask.shape()) labels = Volume<uint32_t>(mask.shape(), mask.geometry());
  labels.set_geometry(mask.geometry());
  const auto back = seg::Neighbourhood::backward(mask.shape(), opt.connectivity);
  UnionFind uf;
  if (opt.phase == Phase::nonzero) first_pass(mask, labels, back, [](uint8_t v) { return v != 0; }, uf);
  else first_pass(mask, labels, back, [](uint8_t v) { return v == 0; }, uf);

  // Roots are the first label of their component, so increasing provisional
  // order numbers the components in raster order of their first voxel.
  const size_t P = uf.parent.size();
  std::vector<uint32_t> final_of(P, 0);
  uint32_t count = 0;
  for (size_t p = 1; p < P; ++p) {
    const uint32_t r = uf.find(uint32_t(p));
    final_of[p] = (r == p) ? ++count : final_of[r];
  }
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

RelabelResult relabel_consecutive(Volume<uint32_t>& labels, int64_t min_size) {
  uint32_t* L = labels.data();
  const int64_t n = labels.size();
  uint32_t maxl = 0;
  for (int64_t i = 0; i < n; ++i) maxl = std::max(maxl, L[i]);
  std::vector<int64_t> size_of(size_t(maxl) + 1, 0);
  for (int64_t i = 0; i < n; ++i) ++size_of[L[i]];
  // New numbers in raster order of first appearance; 0 = dropped/background.
  constexpr uint32_t kUnset = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> to(size_t(maxl) + 1, kUnset);
  to[0] = 0;
  RelabelResult res;
  res.sizes.push_back(0);
  for (int64_t i = 0; i < n; ++i) {
    const uint32_t l = L[i];
    if (to[l] == kUnset) {
      if (size_of[l] >= min_size) {
        to[l] = ++res.count;
        res.sizes.push_back(size_of[l]);
      } else {
        to[l] = 0;
        ++res.dropped;
      }
    }
    L[i] = to[l];
  }
  return res;
}

}  // namespace tg

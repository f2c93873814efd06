// Slivers at the scan's faces (face_slivers.hpp). Serial: the shell is a
// few per cent of the volume, and passes in raster order make the joins
// and claims the same on any thread count.
#include "segmentation/face_slivers.hpp"

#include <algorithm>
#include <limits>

#include "segmentation/neighbourhood.hpp"

namespace tg {

namespace {

// Voxels from the enabled faces, per axis (a large number where neither
// face of the axis is the scan's).
struct FaceDepth {
  Shape s;
  std::array<bool, 6> faces;
  static constexpr int64_t kFar = std::numeric_limits<int64_t>::max() / 4;
  int64_t axis(int64_t v, int64_t n, bool lo, bool hi) const {
    int64_t d = kFar;
    if (lo) d = std::min(d, v);
    if (hi) d = std::min(d, n - 1 - v);
    return d;
  }
  int64_t z(int64_t k) const { return axis(k, s.nz, faces[0], faces[1]); }
  int64_t y(int64_t j) const { return axis(j, s.ny, faces[2], faces[3]); }
  int64_t x(int64_t i) const { return axis(i, s.nx, faces[4], faces[5]); }
};

// f(index, k, j, i, depth) for every voxel within `depth` of an enabled
// face, in raster order.
template <class F>
void for_each_shell_voxel(const Shape& s, const std::array<bool, 6>& faces, int64_t depth, F&& f) {
  const FaceDepth fd{s, faces};
  for (int64_t k = 0; k < s.nz; ++k) {
    const int64_t dz = fd.z(k);
    for (int64_t j = 0; j < s.ny; ++j) {
      const int64_t dzy = std::min(dz, fd.y(j));
      const int64_t row = (k * s.ny + j) * s.nx;
      if (dzy <= depth) {
        for (int64_t i = 0; i < s.nx; ++i) f(row + i, k, j, i, std::min(dzy, fd.x(i)));
        continue;
      }
      // Only the x faces reach into this row.
      const int64_t lo_end = faces[4] ? std::min(depth + 1, s.nx) : 0;
      const int64_t hi_begin = faces[5] ? std::max(lo_end, s.nx - 1 - depth) : s.nx;
      for (int64_t i = 0; i < lo_end; ++i) f(row + i, k, j, i, fd.x(i));
      for (int64_t i = hi_begin; i < s.nx; ++i) f(row + i, k, j, i, fd.x(i));
    }
  }
}

// Calls g(neighbour index) for the 26 neighbours of (k, j, i) inside the volume.
template <class G>
void for_each_neighbour(const Shape& s, int64_t idx, int64_t k, int64_t j, int64_t i, G&& g) {
  for (const seg::Step& d : seg::kSteps) {
    const int64_t kk = k + d.dz, jj = j + d.dy, ii = i + d.dx;
    if (kk < 0 || jj < 0 || ii < 0 || kk >= s.nz || jj >= s.ny || ii >= s.nx) continue;
    g(idx + seg::step_offset(s, d));
  }
}

}  // namespace

std::vector<uint8_t> labels_in_shell(const Volume<uint32_t>& labels, const FaceSliverOptions& opt,
                                     const std::vector<uint32_t>* premap) {
  const uint32_t* L = labels.data();
  size_t nl = premap ? premap->size() : 0;
  if (!premap)
    for_each_shell_voxel(labels.shape(), opt.faces, opt.depth, [&](int64_t q, int64_t, int64_t, int64_t, int64_t) {
      nl = std::max(nl, size_t(L[q]) + 1);
    });
  std::vector<uint8_t> in(nl, 0);
  if (opt.depth < 0) return in;
  for_each_shell_voxel(labels.shape(), opt.faces, opt.depth, [&](int64_t q, int64_t, int64_t, int64_t, int64_t) {
    if (L[q]) in[premap ? (*premap)[L[q]] : L[q]] = 1;
  });
  return in;
}

void grow_face_slivers(Volume<uint32_t>& labels, uint32_t count, const Volume<uint8_t>& grey,
                       const FaceSliverOptions& opt, FaceSliverResult* result) {
  const Shape s = labels.shape();
  if (!(grey.shape() == s)) throw UsageError("face slivers: grey code and labels differ in shape");
  if (opt.depth < 0 || count == 0) return;
  uint32_t* L = labels.data();
  const uint8_t* g = grey.data();
  const FaceDepth fd{s, opt.faces};
  auto coords = [&](int64_t q, int64_t& k, int64_t& j, int64_t& i) {
    i = q % s.nx, j = (q / s.nx) % s.ny, k = q / (s.nx * s.ny);
  };
  // One pass over the shell and the layer behind it: the labels in the
  // shell (their voxels there and brightest voxel), those reaching the
  // layer behind (not thin: a connected label going deeper crosses it, a
  // 26-step changes the depth by at most 1), and the shell's line voxels
  // (unlabelled, above t).
  std::vector<uint8_t> thin(size_t(count) + 1, 0), deep(size_t(count) + 1, 0), peak(size_t(count) + 1, 0);
  std::vector<int64_t> size(size_t(count) + 1, 0);  // a thin label's size
  std::vector<int64_t> lines;
  for_each_shell_voxel(s, opt.faces, opt.depth + 1, [&](int64_t q, int64_t, int64_t, int64_t, int64_t d) {
    const uint32_t l = L[q];
    if (d > opt.depth) {
      if (l && l <= count) deep[l] = 1;
    } else if (l) {
      if (l <= count) thin[l] = 1, ++size[l], peak[l] = std::max(peak[l], g[q]);
    } else if (double(g[q]) > opt.threshold) {
      lines.push_back(q);
    }
  });
  bool any = false;
  for (uint32_t l = 1; l <= count; ++l) thin[l] = thin[l] && !deep[l], any = any || thin[l];
  if (!any) return;
  // A crumb under the size floor beside a label that reaches deeper, across
  // a line voxel, is a piece of that label's grain the watershed cut off:
  // the floor takes it, as without this step.
  std::vector<uint8_t> attached(size_t(count) + 1, 0);
  for (const int64_t q : lines) {
    int64_t k, j, i;
    coords(q, k, j, i);
    bool deeper = false;
    for_each_neighbour(s, q, k, j, i, [&](int64_t n) { deeper = deeper || (L[n] && (L[n] > count || !thin[L[n]])); });
    if (!deeper) continue;
    for_each_neighbour(s, q, k, j, i, [&](int64_t n) {
      const uint32_t l = L[n];
      if (l && l <= count && thin[l] && size[l] < opt.min_size_vox) attached[l] = 1;
    });
  }
  for (uint32_t l = 1; l <= count; ++l)
    if (attached[l]) thin[l] = 0;
  // Thin crumbs meeting across a line voxel, together under crumbs x the
  // floor, are one sliver (the header).
  std::vector<uint32_t> parent(size_t(count) + 1);
  for (uint32_t l = 0; l <= count; ++l) parent[l] = l;
  auto find = [&](uint32_t l) {
    while (parent[l] != l) l = parent[l] = parent[parent[l]];
    return l;
  };
  for (const int64_t q : lines) {
    int64_t k, j, i;
    coords(q, k, j, i);
    uint32_t first = 0;
    bool all_thin = true, two = false;
    for_each_neighbour(s, q, k, j, i, [&](int64_t n) {
      const uint32_t l = L[n];
      if (!l) return;
      all_thin = all_thin && l <= count && thin[l];
      if (first && l != first) two = true;
      if (!first) first = l;
    });
    if (!two || !all_thin) continue;
    for_each_neighbour(s, q, k, j, i, [&](int64_t n) {
      const uint32_t a = find(first), b = L[n] ? find(L[n]) : a;
      if (a == b || size[a] + size[b] >= opt.crumbs * opt.min_size_vox) return;
      const uint32_t lo = std::min(a, b), hi = std::max(a, b);  // the lower number stays
      parent[hi] = lo, size[lo] += size[hi], peak[lo] = std::max(peak[lo], peak[hi]);
    });
  }
  // The thin labels' voxels: the joins written, and the growth's first front.
  std::vector<int64_t> front;
  for_each_shell_voxel(s, opt.faces, opt.depth, [&](int64_t q, int64_t, int64_t, int64_t, int64_t) {
    const uint32_t l = L[q];
    if (l && l <= count && thin[l]) L[q] = find(l), front.push_back(q);
  });
  for (uint32_t l = 1; l <= count; ++l) result->slivers_joined += find(l) != l;
  // Each thin label's level: halfway from the void to its own peak, where
  // that lies below t (a sliver the blur dimmed; the header).
  std::vector<double> low(size_t(count) + 1, opt.threshold);
  for (uint32_t l = 1; l <= count; ++l)
    if (thin[l] && find(l) == l)
      low[l] = std::min(opt.threshold, opt.void_level + opt.half * (double(peak[l]) - opt.void_level));
  // Grows from the front: the unlabelled shell voxels beside it above its
  // label's level whose labelled neighbours are that label alone.
  auto in_shell = [&](int64_t k, int64_t j, int64_t i) {
    return std::min({fd.z(k), fd.y(j), fd.x(i)}) <= opt.depth;
  };
  std::vector<uint8_t> grown(size_t(count) + 1, 0);
  std::vector<int64_t> cand, at;
  std::vector<uint32_t> to;
  for (int round = 0; round < opt.rounds && !front.empty(); ++round) {
    cand.clear();
    for (const int64_t f : front) {
      const uint32_t l = L[f];
      if (!(low[l] < opt.threshold)) continue;  // a bright sliver: as thresholded
      int64_t k, j, i;
      coords(f, k, j, i);
      for (const seg::Step& d : seg::kSteps) {
        const int64_t kk = k + d.dz, jj = j + d.dy, ii = i + d.dx;
        if (kk < 0 || jj < 0 || ii < 0 || kk >= s.nz || jj >= s.ny || ii >= s.nx || !in_shell(kk, jj, ii)) continue;
        const int64_t n = f + seg::step_offset(s, d);
        if (L[n] == 0 && double(g[n]) > low[l]) cand.push_back(n);
      }
    }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    at.clear(), to.clear();
    for (const int64_t q : cand) {
      int64_t k, j, i;
      coords(q, k, j, i);
      uint32_t one = 0;
      bool mixed = false;
      for_each_neighbour(s, q, k, j, i, [&](int64_t n) {
        const uint32_t l = L[n];
        if (!l) return;
        if (one && l != one) mixed = true;
        one = l;
      });
      if (one && !mixed && one <= count && thin[one] && double(g[q]) > low[one]) at.push_back(q), to.push_back(one);
    }
    // Two labels claiming neighbouring voxels in one round would touch:
    // neither claim stands.
    std::vector<uint8_t> ok(at.size(), 1);
    for (size_t c = 0; c < at.size(); ++c) {
      const int64_t q = at[c];
      int64_t k, j, i;
      coords(q, k, j, i);
      for_each_neighbour(s, q, k, j, i, [&](int64_t n) {
        const auto it = std::lower_bound(at.begin(), at.end(), n);
        if (it != at.end() && *it == n && to[size_t(it - at.begin())] != to[c]) ok[c] = 0;
      });
    }
    front.clear();
    for (size_t c = 0; c < at.size(); ++c)
      if (ok[c]) L[at[c]] = to[c], grown[to[c]] = 1, front.push_back(at[c]);
    result->voxels_added += int64_t(front.size());
  }
  for (uint32_t l = 1; l <= count; ++l) result->labels_grown += grown[l];
}

}  // namespace tg

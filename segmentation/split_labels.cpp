#include "segmentation/split_labels.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <omp.h>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "segmentation/distance_transform.hpp"
#include "segmentation/markers.hpp"
#include "segmentation/neighbourhood.hpp"
#include "segmentation/watershed.hpp"

namespace tg {
namespace {

constexpr size_t kBins = 4096;  // flood levels per label (counting sort)
constexpr size_t kConn = 6;  // the flood's neighbourhood (see the header)
constexpr int64_t kScreenPiece = 24;  // the screen's piece: min_piece / 24 (split_one)

int64_t clampi(int64_t v, int64_t lo, int64_t hi) { return v < lo ? lo : (v > hi ? hi : v); }

struct LabelBox {
  int64_t z0 = INT64_MAX, y0 = INT64_MAX, x0 = INT64_MAX, z1 = -1, y1 = -1, x1 = -1;  // inclusive
  int64_t voxels = 0;
  void add_run(int64_t k, int64_t j, int64_t i0, int64_t i1) {  // voxels (k, j, i0..i1)
    z0 = std::min(z0, k), y0 = std::min(y0, j), x0 = std::min(x0, i0);
    z1 = std::max(z1, k), y1 = std::max(y1, j), x1 = std::max(x1, i1);
    voxels += i1 - i0 + 1;
  }
  void add(const LabelBox& o) {
    z0 = std::min(z0, o.z0), y0 = std::min(y0, o.y0), x0 = std::min(x0, o.x0);
    z1 = std::max(z1, o.z1), y1 = std::max(y1, o.y1), x1 = std::max(x1, o.x1);
    voxels += o.voxels;
  }
};

std::vector<LabelBox> label_boxes(const Volume<uint32_t>& labels, uint32_t count) {
  const Shape s = labels.shape();
  const uint32_t* L = labels.data();
  const int nt = omp_get_max_threads();
  std::vector<std::vector<LabelBox>> part(static_cast<size_t>(nt));
#pragma omp parallel num_threads(nt)
  {
    auto& mine = part[size_t(omp_get_thread_num())];
    mine.assign(size_t(count) + 1, LabelBox{});
#pragma omp for schedule(static)
    for (int64_t k = 0; k < s.nz; ++k)
      for (int64_t j = 0; j < s.ny; ++j) {
        const uint32_t* row = L + (k * s.ny + j) * s.nx;
        for (int64_t i = 0; i < s.nx;) {  // by runs of one label: a grain's row is tens of voxels
          const uint32_t l = row[i];
          int64_t e = i + 1;
          while (e < s.nx && row[e] == l) ++e;
          if (l) mine[l].add_run(k, j, i, e - 1);
          i = e;
        }
      }
  }
  std::vector<LabelBox> box(size_t(count) + 1);
  for (const auto& p : part)
    for (uint32_t l = 1; l <= count; ++l)
      if (p[l].voxels) box[l].add(p[l]);
  return box;
}

// Per-thread scratch, reused from label to label.
struct Scratch {
  std::vector<float> a, b, sm, line;    // smoothing passes; sm: the box's smoothed grey
  std::vector<int32_t> raster, order;   // the label's voxels (padded box) in box order, brightest first
  std::vector<int64_t> start;           // counting sort
  // Union-find over box-local voxels. A voxel's parent and smoothed grey
  // share a cache line, and so do a root's size and peak: the flood reads
  // them for the neighbours of each voxel in grey order, all over the box.
  // (Four separate arrays before: the split stage's median at 320^3, R 55,
  // 1.31 -> 1.14 s; 256^3, R 22.7, 0.192 -> 0.174 s; the same labels.)
  struct Node {
    int32_t parent;  // -1: not the label's, or not flooded yet
    float val;       // smoothed grey
  };
  struct Root {
    int32_t size;
    float peak;  // its brightest voxel
  };
  std::vector<Node> node;
  std::vector<Root> root;
};

int32_t find(Scratch::Node* n, int32_t x) {
  while (n[x].parent != x) {
    n[x].parent = n[n[x].parent].parent;
    x = n[x].parent;
  }
  return x;
}

// The box's grey smoothed (step 1 of the header) at every stride-th voxel
// along each axis, into s.sm (ceil(bz / stride) x ceil(by / stride) x
// ceil(bx / stride)); the kernel reads a halo around the box, the volume's
// faces repeated. Stride 2 costs ~40 % of stride 1 (the x pass still reads
// every row of the halo).
template <class T>
void smooth_box(Scratch& s, const Volume<T>& grey, const LabelBox& bx, const std::vector<float>& w, int64_t stride) {
  const Shape S = grey.shape();
  const int64_t r = int64_t(w.size() / 2);
  const int64_t bz = bx.z1 - bx.z0 + 1, by = bx.y1 - bx.y0 + 1, bxn = bx.x1 - bx.x0 + 1;
  const int64_t gz = (bz + stride - 1) / stride, gy = (by + stride - 1) / stride, gx = (bxn + stride - 1) / stride;
  const int64_t ez0 = std::max<int64_t>(0, bx.z0 - r), ez1 = std::min<int64_t>(S.nz - 1, bx.z1 + r);
  const int64_t ey0 = std::max<int64_t>(0, bx.y0 - r), ey1 = std::min<int64_t>(S.ny - 1, bx.y1 + r);
  const int64_t ez = ez1 - ez0 + 1, ey = ey1 - ey0 + 1;
  const T* G = grey.data();
  // x pass: ez x ey x gx. The row's span with its halo (faces repeated) is
  // dealt into `stride` phases, element i to phase i % stride at i / stride,
  // so that each tap reads one phase contiguously: o[i] += w[t] line[i
  // stride + t] with line[i stride + t] = phase[t % stride][i + t / stride].
  // The same sums in the same order as reading the line at a stride, which
  // the compiler did not vectorise (the x pass was most of the smoothing).
  // (Every element a tap reads, i stride + t < span, is dealt.)
  const int64_t span = bxn + 2 * r, plen = (span + stride - 1) / stride;
  const int64_t in0 = std::max<int64_t>(0, r - bx.x0), in1 = std::min(span, S.nx - bx.x0 + r);  // inside the row
  s.a.resize(size_t(ez * ey * gx));
  s.line.resize(size_t(stride * plen));
  for (int64_t k = 0; k < ez; ++k)
    for (int64_t j = 0; j < ey; ++j) {
      const T* row = G + ((ez0 + k) * S.ny + (ey0 + j)) * S.nx;
      const int64_t x0 = bx.x0 - r;  // the span's first voxel (may lie before the row)
      float* phase = s.line.data();
      for (int64_t p = 0; p < stride; ++p) {
        float* out = phase + p * plen;
        int64_t i = p;
        for (; i < in0; i += stride) *out++ = float(row[0]);  // before the row: its first voxel
        for (; i < in1; i += stride) *out++ = float(row[x0 + i]);
        for (; i < span; i += stride) *out++ = float(row[S.nx - 1]);  // after it: its last
      }
      float* __restrict o = s.a.data() + (k * ey + j) * gx;
      std::fill(o, o + gx, 0.0f);
      for (int64_t t = 0; t <= 2 * r; ++t) {
        const float wt = w[size_t(t)];
        const float* __restrict in = phase + (t % stride) * plen + t / stride;
        for (int64_t i = 0; i < gx; ++i) o[i] += wt * in[i];
      }
    }
  // y pass: ez x gy x gx
  s.b.resize(size_t(ez * gy * gx));
  for (int64_t k = 0; k < ez; ++k)
    for (int64_t j = 0; j < gy; ++j) {
      float* o = s.b.data() + (k * gy + j) * gx;
      std::fill(o, o + gx, 0.0f);
      for (int64_t t = -r; t <= r; ++t) {
        const int64_t jj = clampi(bx.y0 + j * stride + t, 0, S.ny - 1) - ey0;
        const float* in = s.a.data() + (k * ey + jj) * gx;
        const float wt = w[size_t(t + r)];
        for (int64_t i = 0; i < gx; ++i) o[i] += wt * in[i];
      }
    }
  // z pass: gz x gy x gx
  s.sm.resize(size_t(gz * gy * gx));
  for (int64_t k = 0; k < gz; ++k) {
    float* o = s.sm.data() + k * gy * gx;
    std::fill(o, o + gy * gx, 0.0f);
    for (int64_t t = -r; t <= r; ++t) {
      const int64_t kk = clampi(bx.z0 + k * stride + t, 0, S.nz - 1) - ez0;
      const float* in = s.b.data() + kk * gy * gx;
      const float wt = w[size_t(t + r)];
      for (int64_t q = 0; q < gy * gx; ++q) o[q] += wt * in[q];
    }
  }
}

// The flood of step 2 (header) over the label's voxels at a stride (1:
// all; 2: every second along each axis) of its box, on the box padded by
// one voxel (never the label's), so that the neighbours need no bounds
// test. Returns whether significant components were kept apart; with
// screen, at the first such event. Leaves the union-find in s.node for
// the pieces (stride 1).
bool flood_box(Scratch& s, const uint32_t* L, uint32_t l, const Shape& S, const LabelBox& bx, int64_t bz, int64_t by,
               int64_t bxn, int64_t stride, int64_t vmin, float depth, float floor_level, bool screen) {
  const int64_t gz = (bz + stride - 1) / stride, gy = (by + stride - 1) / stride, gx = (bxn + stride - 1) / stride;
  const float* sm = s.sm.data();  // smooth_box at this stride
  const int64_t py = gy + 2, px = gx + 2, pn = (gz + 2) * py * px;
  if (pn > int64_t(INT32_MAX)) throw std::logic_error("split_by_grey: box too large");
  // Only the parents need a fill (-1: not the label's, or not flooded yet);
  // the greys and the roots are read only where the label's voxels set them.
  s.node.resize(size_t(pn));
  for (Scratch::Node& x : s.node) x.parent = -1;
  Scratch::Node* node = s.node.data();
  s.raster.clear();
  float hi = -1.0f, lo = 3.0e38f;
  for (int64_t k = 0; k < bz; k += stride)
    for (int64_t j = 0; j < by; j += stride) {
      const uint32_t* row = L + ((bx.z0 + k) * S.ny + (bx.y0 + j)) * S.nx + bx.x0;
      for (int64_t i = 0; i < bxn; i += stride)
        if (row[i] == l) {
          const int32_t q = int32_t(((k / stride + 1) * py + (j / stride + 1)) * px + (i / stride + 1));
          const float v = sm[((k / stride) * gy + j / stride) * gx + i / stride];
          node[q].val = v;
          s.raster.push_back(q);
          hi = std::max(hi, v), lo = std::min(lo, v);
        }
    }
  // Brightest first, by a stable counting sort into levels between the
  // label's extremes (at most 4096: a few grey levels each, far below any
  // depth that matters); within a level, box order.
  {
    // As many levels as voxels, 256 to kBins: the fill of the counts costs
    // no more than the voxels themselves.
    const size_t bins = std::clamp<size_t>(s.raster.size(), 256, kBins);
    const float width = std::max(hi - lo, 1e-6f) / float(bins - 1);
    auto bin = [&](float v) { return std::min<size_t>(bins - 1, size_t((hi - v) / width)); };
    s.start.assign(bins + 1, 0);
    for (const int32_t q : s.raster) ++s.start[bin(node[q].val) + 1];
    for (size_t b = 0; b < bins; ++b) s.start[b + 1] += s.start[b];
    s.order.resize(s.raster.size());
    for (const int32_t q : s.raster) s.order[size_t(s.start[bin(node[q].val)]++)] = q;
  }
  std::array<int64_t, kConn> off;
  for (size_t d = 0; d < kConn; ++d) off[d] = (int64_t(seg::kSteps[d].dz) * py + seg::kSteps[d].dy) * px + seg::kSteps[d].dx;
  s.root.resize(size_t(pn));
  bool separated = false;
  int32_t roots[kConn];
  float reach[kConn];  // per root: its brightest voxel among this voxel's neighbours
  Scratch::Root* root = s.root.data();
  auto significant = [&](int32_t rt, float v) { return root[rt].size >= vmin && root[rt].peak - v >= depth; };
  // Union by size (short finds); the root carries the larger peak.
  auto unite = [&](int32_t x, int32_t y) {
    if (root[x].size < root[y].size || (root[x].size == root[y].size && y < x)) std::swap(x, y);
    node[y].parent = x;
    root[x].size += root[y].size;
    root[x].peak = std::max(root[x].peak, root[y].peak);
    return x;
  };
  for (const int32_t q : s.order) {
    const float v = node[q].val;
    // Below the floor with nothing kept apart yet: no split (a sheet darker
    // than the threshold even smoothed is void in the mask, the watershed's
    // business); the rim of every grain is not flooded for nothing.
    if (v < floor_level && !separated) return false;
    int nr = 0;
    for (size_t d = 0; d < kConn; ++d) {
      const int32_t nq = int32_t(q + off[d]);
      if (node[nq].parent < 0) continue;  // not the label's, or not flooded yet
      const float vn = node[nq].val;
      const int32_t rt = find(node, nq);
      const int a = int(std::find(roots, roots + nr, rt) - roots);
      if (a == nr) {
        roots[nr] = rt;
        reach[nr++] = vn;
      } else {
        reach[a] = std::max(reach[a], vn);
      }
    }
    node[q].parent = q;
    root[q] = {1, v};
    if (nr == 0) continue;
    // The significant components this voxel touches; it goes to the one
    // of its brightest neighbour (steepest ascent, as a flood reaches it;
    // the highest peak instead let a large grain creep round the rim of a
    // chip beside it, voxel by voxel).
    int nsig = 0, best = -1;
    for (int a = 0; a < nr; ++a)
      if (significant(roots[a], v)) {
        ++nsig;
        if (best < 0 || reach[a] > reach[best] || (reach[a] == reach[best] && roots[a] < roots[best])) best = a;
      }
    int32_t into;
    if (nsig >= 2) {
      if (screen) return true;
      separated = true;
      into = roots[best];
      for (int a = 0; a < nr; ++a)  // the lesser components go with the voxel; the significant ones stay apart
        if (a != best && !significant(roots[a], v)) into = unite(into, roots[a]);
    } else {
      into = roots[0];
      for (int a = 1; a < nr; ++a) into = unite(into, roots[a]);
    }
    node[q].parent = into;
    root[into].size += 1;
  }
  return separated;
}

// The pieces of one label (count 1: no split). The largest keeps the
// label; the voxels of the others are listed with their piece ordinal.
struct Pieces {
  std::vector<int64_t> voxel;  // global indices of the voxels that leave the label
  std::vector<int32_t> piece;  // their piece ordinal, 1..n-1
  int32_t count = 1;
  bool no_core = false;        // thin_pieces_one: no voxel of the label deeper than the radius
};

template <class T>
Pieces split_one(const Volume<uint32_t>& labels, const Volume<T>& grey, uint32_t l, const LabelBox& bx,
                 const std::vector<float>& w, const SplitOptions& opt, Scratch& s) {
  Pieces out;
  const Shape S = labels.shape();
  const int64_t bz = bx.z1 - bx.z0 + 1, by = bx.y1 - bx.y0 + 1, bxn = bx.x1 - bx.x0 + 1;
  const uint32_t* L = labels.data();
  const int64_t vmin = std::max<int64_t>(opt.min_piece_vox, int64_t(std::ceil(opt.min_piece_fraction * double(bx.voxels))));
  // Screen: the same flood on every second voxel along each axis (1/8 of
  // the work), with half the depth and 1/kScreenPiece of the piece. Most
  // labels are whole and stop here. A thin piece (a chip 2-4 voxels thick
  // above the sheet) shows far fewer than an eighth of its voxels on the
  // coarse grid, whose sheet also sits higher: a chip of 191 voxels above
  // its sheet had 10 there (bench/segmentation/RESULTS.md "Thin pieces in
  // the split repair's screen"). With an eighth, the screen dropped 7 of
  // the splits the full flood makes on 18 middle-setting scenes (R 16 and
  // 20); with 1/16 one, with 1/24 none, at +0.02 s at 256^3 (85 full floods
  // of 574 labels instead of 68).
  smooth_box(s, grey, bx, w, 2);
  if (!flood_box(s, L, l, S, bx, bz, by, bxn, 2, std::max<int64_t>(4, vmin / kScreenPiece), 0.5f * float(opt.depth),
                 float(opt.floor), true))
    return out;
  smooth_box(s, grey, bx, w, 1);
  if (!flood_box(s, L, l, S, bx, bz, by, bxn, 1, vmin, float(opt.depth), float(opt.floor), false)) return out;
  const int64_t py = by + 2, px = bxn + 2;

  // Pieces: the final components of at least vmin voxels; the largest keeps
  // the label (ties: the first in box order), smaller leftovers too.
  std::vector<std::pair<int32_t, int32_t>> big;  // (root, size)
  for (const int32_t q : s.order)
    if (s.node[size_t(q)].parent == q && s.root[size_t(q)].size >= vmin) big.emplace_back(q, s.root[size_t(q)].size);
  if (big.size() < 2) return out;
  std::sort(big.begin(), big.end(), [](const auto& a, const auto& b) { return a.second > b.second || (a.second == b.second && a.first < b.first); });
  std::vector<std::pair<int32_t, int32_t>> ordinal;  // (root, piece) for pieces 1..
  for (size_t p = 1; p < big.size(); ++p) ordinal.emplace_back(big[p].first, int32_t(p));
  std::sort(ordinal.begin(), ordinal.end());
  for (const int32_t q : s.raster) {
    const int32_t rt = find(s.node.data(), q);
    const auto it = std::lower_bound(ordinal.begin(), ordinal.end(), std::make_pair(rt, int32_t(0)));
    if (it == ordinal.end() || it->first != rt) continue;
    const int64_t k = q / (py * px) - 1, j = (q / px) % py - 1, i = q % px - 1;
    out.voxel.push_back(((bx.z0 + k) * S.ny + (bx.y0 + j)) * S.nx + bx.x0 + i);
    out.piece.push_back(it->second);
  }
  out.count = int32_t(big.size());
  return out;
}

// Gives the voxels of every piece but the largest (which keeps the label)
// their new numbers, next + 1 on; false when there is one piece only.
bool renumber_pieces(uint32_t* L, const Pieces& p, uint32_t& next, const char* repair) {
  if (p.count < 2) return false;
  if (uint64_t(next) + uint64_t(p.count) > uint64_t(UINT32_MAX))
    throw ResourceError(std::string("segment: more than 2^32 - 1 labels after the ") + repair);
  for (size_t v = 0; v < p.voxel.size(); ++v) L[p.voxel[v]] = next + uint32_t(p.piece[v]);
  next += uint32_t(p.count - 1);
  return true;
}

// Numbers the pieces of labels 1..n (pieces[l]) in label order, from
// n + 1 on: the same whatever the thread count that found them. Counts the
// labels split and the pieces added; *count becomes the last number.
void apply_pieces(uint32_t* L, const std::vector<Pieces>& pieces, uint32_t n, uint32_t* count, const char* repair,
                  int64_t* split, int64_t* added) {
  uint32_t next = n;
  for (uint32_t l = 1; l <= n; ++l) {
    const Pieces& p = pieces[l];
    if (!renumber_pieces(L, p, next, repair)) continue;
    ++*split;
    *added += p.count - 1;
  }
  *count = next;
}

template <class T>
SplitResult split_impl(Volume<uint32_t>& labels, uint32_t* count, const Volume<T>& grey, const SplitOptions& opt) {
  if (!(labels.shape() == grey.shape())) throw std::logic_error("split_by_grey: labels and grey differ in shape");
  SplitResult res;
  const std::vector<float> w = gaussian_kernel(opt.smoothing_sigma_vox);
  const uint32_t n = *count;
  if (n == 0) return res;
  const std::vector<LabelBox> box = label_boxes(labels, n);
  std::vector<Pieces> pieces(size_t(n) + 1);
  int64_t tested = 0, skipped = 0;
#pragma omp parallel reduction(+ : tested, skipped)
  {
    Scratch s;
#pragma omp for schedule(dynamic, 1)
    for (int64_t l = 1; l <= int64_t(n); ++l) {
      const LabelBox& b = box[size_t(l)];
      const int64_t vmin =
          std::max<int64_t>(opt.min_piece_vox, int64_t(std::ceil(opt.min_piece_fraction * double(b.voxels))));
      if (b.voxels < 2 * vmin) continue;
      const int64_t bv = (b.z1 - b.z0 + 1) * (b.y1 - b.y0 + 1) * (b.x1 - b.x0 + 1);
      if (bv > opt.max_box_vox || bv > int64_t(INT32_MAX)) {
        ++skipped;
        continue;
      }
      ++tested;
      pieces[size_t(l)] = split_one(labels, grey, uint32_t(l), b, w, opt, s);
    }
  }
  res.tested = tested;
  res.skipped_large = skipped;
  apply_pieces(labels.data(), pieces, n, count, "split repair", &res.split, &res.pieces_added);
  return res;
}

}  // namespace

SplitResult split_by_grey(Volume<uint32_t>& labels, uint32_t* count, const Volume<uint16_t>& grey,
                          const SplitOptions& opt) {
  return split_impl(labels, count, grey, opt);
}
SplitResult split_by_grey(Volume<uint32_t>& labels, uint32_t* count, const Volume<uint8_t>& grey,
                          const SplitOptions& opt) {
  return split_impl(labels, count, grey, opt);
}

GreyCode GreyCode::from_histogram(const std::vector<int64_t>& hist) {
  int64_t n = 0;
  for (const int64_t c : hist) n += c;
  GreyCode g;
  if (n == 0) return g;
  size_t lo = 0, hi = hist.size() - 1;
  for (int64_t c = 0; lo < hist.size(); ++lo)
    if ((c += hist[lo]) > n / 1000) break;
  for (int64_t c = 0; hi > 0; --hi)
    if ((c += hist[hi]) > n / 1000) break;
  g.lo = double(std::min(lo, hi));
  g.step = std::max(1.0, (double(hi) - g.lo) / 255.0);
  return g;
}

Volume<uint8_t> quantise_grey(const Volume<uint16_t>& grey, const GreyCode& code) {
  Volume<uint8_t> out(grey.shape(), grey.geometry());
  std::vector<uint8_t> lut(65536);  // one rounding per grey level, not per voxel
  for (size_t g = 0; g < lut.size(); ++g)
    lut[g] = uint8_t(std::clamp(std::lround((double(g) - code.lo) / code.step), 0L, 255L));
  const uint16_t* g = grey.data();
  uint8_t* o = out.data();
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < grey.size(); ++i) o[i] = lut[g[i]];
  return out;
}

void smoothed_sample_histogram(const Volume<uint16_t>& slab, int64_t z0, int64_t nz_scan, const FieldOfView& fov,
                               double smoothing_sigma_vox, std::vector<int64_t>& hist, std::vector<int64_t>* pairs) {
  if (hist.size() != 65536) hist.assign(65536, 0);
  if (pairs && pairs->size() != kPairLevelBins * kPairDiffBins) pairs->assign(kPairLevelBins * kPairDiffBins, 0);
  const std::vector<float> w = gaussian_kernel(smoothing_sigma_vox);
  const int64_t r = int64_t(w.size() / 2);
  const Shape S = slab.shape();
  const int64_t plane = S.ny * S.nx;
  std::vector<int64_t> zs;
  if (nz_scan <= 8) {
    if (nz_scan / 2 >= z0 && nz_scan / 2 < z0 + S.nz) zs.push_back(nz_scan / 2);
  } else {
    for (int64_t z = z0 + ((8 - z0 % 16) % 16 + 16) % 16; z < z0 + S.nz; z += 16) zs.push_back(z);
  }
  std::vector<float> a(static_cast<size_t>(plane)), b(static_cast<size_t>(plane));
  // Each thread's counts over all the sample slices, summed at the end (a
  // fresh 65536-bin table a thread and a slice, and their sums in a
  // critical section, cost more than the slices' smoothing at 256^3).
  std::vector<std::vector<int64_t>> part(static_cast<size_t>(omp_get_max_threads()), std::vector<int64_t>(65536, 0));
  std::vector<std::vector<int64_t>> pair_part(pairs ? part.size() : 0,
                                              std::vector<int64_t>(kPairLevelBins * kPairDiffBins, 0));
  std::vector<float> c(pairs ? static_cast<size_t>(plane) : 0);  // the smoothed slice, for the pairs
  const uint16_t* G = slab.data();
  for (const int64_t z : zs) {
    // z pass: the slice's neighbours, the scan's end faces repeated.
    std::fill(a.begin(), a.end(), 0.0f);
    for (int64_t t = -r; t <= r; ++t) {
      const int64_t zz = clampi(z + t, 0, nz_scan - 1) - z0;
      if (zz < 0 || zz >= S.nz)
        throw std::logic_error("smoothed_sample_histogram: a sample slice's neighbours lie outside the slab");
      const uint16_t* in = G + zz * plane;
      const float wt = w[size_t(t + r)];
#pragma omp parallel for schedule(static)
      for (int64_t q = 0; q < plane; ++q) a[size_t(q)] += wt * float(in[q]);
    }
    // y pass, then x pass with the histogram.
#pragma omp parallel for schedule(static)
    for (int64_t j = 0; j < S.ny; ++j)
      for (int64_t i = 0; i < S.nx; ++i) {
        float acc = 0;
        for (int64_t t = -r; t <= r; ++t) acc += w[size_t(t + r)] * a[size_t(clampi(j + t, 0, S.ny - 1) * S.nx + i)];
        b[size_t(j * S.nx + i)] = acc;
      }
#pragma omp parallel
    {
      std::vector<int64_t>& hl = part[size_t(omp_get_thread_num())];
#pragma omp for schedule(static) nowait
      for (int64_t j = 0; j < S.ny; ++j) {
        const int64_t lo = fov.active ? fov.x0[size_t(j)] : 0, hi = fov.active ? fov.x1[size_t(j)] : S.nx;
        for (int64_t i = lo; i < hi; ++i) {
          float acc = 0;
          for (int64_t t = -r; t <= r; ++t) acc += w[size_t(t + r)] * b[size_t(j * S.nx + clampi(i + t, 0, S.nx - 1))];
          ++hl[size_t(clampi(std::lround(acc), 0, 65535))];
          if (pairs) c[size_t(j * S.nx + i)] = acc;
        }
      }
    }
    if (!pairs) continue;
    // The pairs: rows 2 in from the slice's edges, pixels 2 in from the
    // field of view's ends in the row.
    constexpr int64_t m = 2, d = kPairStepVox;
    // The raw grey 2 slices below and above: a pixel of a slice that cuts a
    // body near its top or bottom is partial volume too.
    const int64_t zb = clampi(z - m, 0, nz_scan - 1) - z0, za = clampi(z + m, 0, nz_scan - 1) - z0;
    if (zb < 0 || za >= S.nz)
      throw std::logic_error("smoothed_sample_histogram: a sample slice's pair check lies outside the slab");
    const uint16_t* below = G + zb * plane;
    const uint16_t* above = G + za * plane;
#pragma omp parallel
    {
      std::vector<int64_t>& pl = pair_part[size_t(omp_get_thread_num())];
      std::vector<float> low(static_cast<size_t>(S.nx));
#pragma omp for schedule(static) nowait
      for (int64_t j = m; j < S.ny - m; ++j) {
        const int64_t lo = fov.active ? std::max(fov.x0[size_t(j - m)], fov.x0[size_t(j + m)]) : 0;
        const int64_t hi = fov.active ? std::min(fov.x1[size_t(j - m)], fov.x1[size_t(j + m)]) : S.nx;
        const float* row = &c[size_t(j * S.nx)];
        for (int64_t i = lo; i < hi; ++i)
          low[size_t(i)] = std::min({row[i], row[i - m * S.nx], row[i + m * S.nx], float(below[j * S.nx + i]),
                                     float(above[j * S.nx + i])});
        for (int64_t i = lo + m; i + d + m < hi; i += 2) {  // every other pixel: enough pairs at half the cost
          float level = row[i - m];
          for (int64_t q = i - m + 1; q <= i + d + m; ++q) level = std::min(level, row[q]);
          level = std::min({level, low[size_t(i)], low[size_t(i + d)]});
          const double diff = std::abs(double(row[i + d]) - double(row[i]));
          const size_t lb = size_t(clampi(std::lround(level), 0, 65535)) >> kPairLevelShift;
          ++pl[lb * kPairDiffBins + size_t(std::min<double>(double(kPairDiffBins - 1), diff / kPairDiffStep))];
        }
      }
    }
  }
  for (const auto& hl : part)
    for (size_t g = 0; g < hl.size(); ++g) hist[g] += hl[g];
  for (const auto& pl : pair_part)
    for (size_t g = 0; g < pl.size(); ++g) (*pairs)[g] += pl[g];
}

std::vector<float> gaussian_kernel(double sigma) {
  if (!(sigma > 0) || !std::isfinite(sigma)) throw UsageError("segment: a Gaussian smoothing must be > 0 voxels");
  const int r = int(std::ceil(3.0 * sigma));
  std::vector<double> w(size_t(2 * r + 1));
  double sum = 0;
  for (int k = -r; k <= r; ++k) sum += w[size_t(k + r)] = std::exp(-0.5 * double(k * k) / (sigma * sigma));
  std::vector<float> f(w.size());
  for (size_t k = 0; k < w.size(); ++k) f[k] = float(w[k] / sum);
  return f;
}

double white_noise_gain(double smoothing_sigma_vox) {
  double w2 = 0;
  for (const float w : gaussian_kernel(smoothing_sigma_vox)) w2 += double(w) * double(w);
  return std::pow(w2, 1.5);
}

WithinGrain within_grain_sigma(const std::vector<int64_t>& pairs, uint16_t t, int64_t min_pairs) {
  WithinGrain r;
  if (pairs.size() != kPairLevelBins * kPairDiffBins) return r;
  // Level bins wholly above t: both pixels of the pair two voxels inside a body.
  const size_t first = (size_t(t) >> kPairLevelShift) + 1;
  std::vector<int64_t> diff(kPairDiffBins, 0);
  for (size_t lb = first; lb < kPairLevelBins; ++lb)
    for (size_t k = 0; k < kPairDiffBins; ++k) diff[k] += pairs[lb * kPairDiffBins + k];
  for (const int64_t n : diff) r.pairs += n;
  if (r.pairs < std::max<int64_t>(min_pairs, 1)) return r;
  int64_t c = 0;
  for (size_t k = 0; k < kPairDiffBins; ++k) {
    if (2 * (c + diff[k]) >= r.pairs) {  // the median inside bin k, linearly
      const double frac = diff[k] ? (0.5 * double(r.pairs) - double(c)) / double(diff[k]) : 0.0;
      r.sigma = (double(k) + std::clamp(frac, 0.0, 1.0)) * kPairDiffStep / (0.6745 * std::sqrt(2.0));
      break;
    }
    c += diff[k];
  }
  return r;
}

namespace {

// One face of the volume: axis a (0 z, 1 y, 2 x) at coordinate c; the face
// slice's pixels (u, v) run over the two other axes in (z, y, x) order.
struct Face {
  int a = 0;
  int64_t c = 0, nu = 0, nv = 0;
  int64_t index(const Shape& S, int64_t u, int64_t v) const {
    if (a == 0) return S.index(c, u, v);
    if (a == 1) return S.index(u, c, v);
    return S.index(u, v, c);
  }
};

struct Box2 {
  int64_t u0 = INT64_MAX, u1 = -1, v0 = INT64_MAX, v1 = -1;
};

// The part of a footprint's piece that seeds the flood in depth: its
// pixels at least this share of the piece's deepest (the core of the disc,
// not the rim where two discs meet).
constexpr float kFaceSeedCore = 0.5f;

struct Seed {
  int64_t voxel;  // global index, on the face (or behind it: step 1b)
  uint32_t id;    // 1.. (the footprint's significant maxima)
};

// A label's seeds, and whether they come from step 1b (a cap in front of a
// neighbour), which asks the sheet for a contact's dip (min_dip_in_front).
struct CapCandidate {
  std::vector<Seed> seeds;
  bool in_front = false;
};

// Step 1b of the header: a footprint with one maximum, the cap's, whose
// label goes on behind it into a neighbour (the cap is pressed on its
// pole, so the label's sections grow inward as one grain's would). Walks
// the cylinder over the footprint's core (`core`, face pixels) inward: the
// mean raw grey of the label's voxels in it, layer by layer. The cap is
// thin: a cap deeper than half its footprint's radius is a good part of a
// grain, with a distance maximum, so a marker, of its own (dev scenes:
// caps pressed on a neighbour 1-2 voxels deep; a dim layer deeper is a
// pore, 4-17 voxels in on the pores 2-4 and PSF 1.5 scenes of the sweep).
// So the layer at depth 1..max(1, top/2) where the label thins out (under
// 30 % of the core) or darkens by min_dip of the solid's height is the
// back of the cap; a layer deeper (by at most top+4) that is the label's
// again and as bright as solid (within kCapBackBright) is a body behind
// it. One convex grain's chords along the normal neither leave it and
// come back nor cross a dim sheet, but a pore in the cylinder darkens a
// layer too: the sheet test of step 3 decides, at min_dip_in_front.
// Returns the seeds (the face core and the cylinder above the dim layer:
// 1; the bright layer: 2) or none. Dev scenes: blind_scene.py R 16 seeds
// 401-406 (and 302 for the sheet's dip), stage 4 scans of blind_series R 14
// and R 18 (the face layer); bench/segmentation/RESULTS.md "Caps in front
// of a neighbour".
constexpr double kCapBackBright = 0.1;

std::vector<Seed> cap_in_front_seeds(const Volume<uint32_t>& labels, const Volume<uint8_t>& grey, uint32_t l,
                                     const Face& f, const std::vector<int64_t>& core, float top,
                                     const FaceCapOptions& opt) {
  const Shape S = labels.shape();
  const uint32_t* L = labels.data();
  const uint8_t* G = grey.data();
  const double height = opt.solid - opt.floor;
  if (core.empty() || !(height > 0)) return {};
  const int64_t dims[3] = {S.nz, S.ny, S.nx};
  const int64_t stride = f.a == 0 ? S.slice_voxels() : (f.a == 1 ? S.nx : 1);
  const int64_t inward = f.c == 0 ? stride : -stride;
  const int64_t n_core = int64_t(core.size());
  const int64_t enough = std::max<int64_t>(3, (3 * n_core + 9) / 10);
  const int64_t dip_last = std::max<int64_t>(1, int64_t(top / 2));
  // Layer d of the cylinder: how many core pixels are label l there, and
  // the darkness (solid - mean grey) / height of those.
  auto layer = [&](int64_t d, double& dark) {
    int64_t n = 0;
    double sum = 0;
    for (int64_t g : core) {
      const int64_t q = g + d * inward;
      if (L[q] == l) ++n, sum += G[q];
    }
    dark = n ? (opt.solid - sum / double(n)) / height : 1.0;
    return n;
  };
  // The cap is solid where the face cuts it. A piece of one grain only a
  // voxel or two thick at the face is partial-volume dim through, and its
  // "back" is its own far surface (late-stage scans: face layers 0.35-0.67
  // dark on every such false cap, 0.01-0.23 on the caps pressed on a
  // neighbour, dev scenes R 14-18 stage 4 and R 16 seeds 402-406).
  double front = 0;
  if (layer(0, front) < enough || front >= opt.min_dip) return {};
  int64_t back = -1, body = -1;
  for (int64_t d = 1; d < dims[f.a] && d <= dip_last + int64_t(std::ceil(top)) + 4; ++d) {
    double dark = 0;
    const int64_t n = layer(d, dark);
    if (back < 0) {
      if (d > dip_last) break;
      if (n < enough || dark >= opt.min_dip) back = d;
    } else if (d > back + int64_t(std::ceil(top)) + 4) {
      break;
    } else if (n >= enough && dark < kCapBackBright) {
      body = d;
      break;
    }
  }
  if (body < 0) return {};
  std::vector<Seed> seeds;
  for (int64_t g : core) {
    for (int64_t d = 0; d < back; ++d)
      if (L[g + d * inward] == l) seeds.push_back({g + d * inward, 1});
    if (L[g + body * inward] == l) seeds.push_back({g + body * inward, 2});
  }
  return seeds;
}

// Step 1 of the header for label l's footprint within `b` on face f: the
// seeds (empty: not a candidate).
CapCandidate footprint_seeds(const Volume<uint32_t>& labels, const Volume<uint8_t>& grey, uint32_t l, const Face& f,
                             const Box2& b, const FaceCapOptions& opt) {
  const Shape S = labels.shape();
  const uint32_t* L = labels.data();
  const int64_t u0 = std::max<int64_t>(b.u0 - 1, 0), u1 = std::min(b.u1 + 1, f.nu - 1);
  const int64_t v0 = std::max<int64_t>(b.v0 - 1, 0), v1 = std::min(b.v1 + 1, f.nv - 1);
  const int64_t hu = u1 - u0 + 1, hv = v1 - v0 + 1;
  Volume<uint8_t> fp(Shape{1, hu, hv});
  uint8_t* F = fp.data();
  int64_t area = 0;
  for (int64_t u = 0; u < hu; ++u)
    for (int64_t v = 0; v < hv; ++v) area += F[u * hv + v] = L[f.index(S, u0 + u, v0 + v)] == l;
  // Holes: the pixels no 4-path of non-footprint pixels joins to the box's
  // border (pores cut by the face) become footprint.
  std::vector<int64_t> stack;
  auto visit = [&](int64_t q) {
    if (F[q] == 0) F[q] = 2, stack.push_back(q);
  };
  for (int64_t u = 0; u < hu; ++u) visit(u * hv), visit(u * hv + hv - 1);
  for (int64_t v = 0; v < hv; ++v) visit(v), visit((hu - 1) * hv + v);
  while (!stack.empty()) {
    const int64_t q = stack.back();
    stack.pop_back();
    const int64_t u = q / hv, v = q % hv;
    if (u > 0) visit(q - hv);
    if (u + 1 < hu) visit(q + hv);
    if (v > 0) visit(q - 1);
    if (v + 1 < hv) visit(q + 1);
  }
  for (int64_t q = 0; q < hu * hv; ++q) F[q] = F[q] == 2 ? 0 : 1;
  if (double(area) < M_PI * opt.min_peak * opt.min_peak) return {};  // no room for a disc min_peak deep
  EdtOptions eo;
  const std::array<double, 3> sp = opt.spacing;
  eo.spacing = f.a == 0 ? std::array<double, 3>{1.0, sp[1], sp[2]}
               : f.a == 1 ? std::array<double, 3>{1.0, sp[0], sp[2]}
                          : std::array<double, 3>{1.0, sp[0], sp[1]};
  Volume<float> dist;
  distance_transform(fp, dist, eo);
  const float* D = dist.data();
  for (int64_t q = 0; q < hu * hv; ++q)
    if (!std::isfinite(D[q])) return {};  // the footprint fills the whole face
  Volume<uint32_t> markers;
  const uint32_t k = find_markers(dist, markers, {opt.h, 26});
  if (k == 0 || (k == 1 && !opt.caps_in_front)) return {};
  const uint32_t* M = markers.data();
  std::vector<float> peak(size_t(k) + 1, 0.0f);
  for (int64_t q = 0; q < hu * hv; ++q) peak[M[q]] = std::max(peak[M[q]], D[q]);
  std::vector<uint32_t> id(size_t(k) + 1, 0);
  uint32_t deep = 0;
  for (uint32_t m = 1; m <= k; ++m)
    if (peak[m] >= opt.min_peak) id[m] = ++deep;
  if (deep == 0) return {};
  if (deep >= 2 && double(area) < 2 * M_PI * opt.min_peak * opt.min_peak) return {};  // no room for two discs
  if (deep == 1) {
    if (!opt.caps_in_front) return {};
    float top1 = 0;
    for (uint32_t m = 1; m <= k; ++m)
      if (id[m]) top1 = peak[m];
    std::vector<int64_t> core;
    for (int64_t u = 0; u < hu; ++u)
      for (int64_t v = 0; v < hv; ++v) {
        const int64_t g = f.index(S, u0 + u, v0 + v);
        if (L[g] == l && D[u * hv + v] >= kFaceSeedCore * top1) core.push_back(g);
      }
    return {cap_in_front_seeds(labels, grey, l, f, core, top1, opt), true};
  }
  // The whole footprint parted among the deep maxima (a watershed of its
  // distance map, no lines), and the core of each part seeds the flood in
  // depth: seeded at the maxima alone, the neighbour's front took much of a
  // thin cap (dev scenes: the caps' IoU 0.35-0.74 against 0.56-0.88).
  uint32_t* Mw = markers.data();
  for (int64_t q = 0; q < hu * hv; ++q) Mw[q] = id[Mw[q]];
  watershed(dist, fp, markers, {false, 26, 4.0});
  std::vector<float> top(size_t(deep) + 1, 0.0f);
  for (uint32_t m = 1; m <= k; ++m)
    if (id[m]) top[id[m]] = peak[m];
  std::vector<Seed> seeds;
  for (int64_t u = 0; u < hu; ++u)
    for (int64_t v = 0; v < hv; ++v) {
      const int64_t g = f.index(S, u0 + u, v0 + v);
      const uint32_t m = M[u * hv + v];
      if (m && L[g] == l && D[u * hv + v] >= kFaceSeedCore * top[m]) seeds.push_back({g, m});
    }
  return {seeds, false};
}

// Steps 2 and 3 for one candidate: the voxels that leave label l, with
// their piece ordinal 1.. (Pieces::count - 1 new labels).
Pieces split_cap(const Volume<uint32_t>& labels, const Volume<uint8_t>& grey, uint32_t l, const LabelBox& bx,
                 const std::vector<Seed>& seeds, double min_dip, const FaceCapOptions& opt) {
  Pieces out;
  const Shape S = labels.shape();
  const uint32_t* L = labels.data();
  const uint8_t* G = grey.data();
  // The label's box, one voxel wider where it is not at a face of the
  // volume: there the neighbouring voxels are not the label's (void for
  // its distance map), beyond a face nothing is (not void, as segment()'s
  // distance map).
  const int64_t z0 = std::max<int64_t>(bx.z0 - 1, 0), y0 = std::max<int64_t>(bx.y0 - 1, 0),
                x0 = std::max<int64_t>(bx.x0 - 1, 0);
  const int64_t z1 = std::min(bx.z1 + 1, S.nz - 1), y1 = std::min(bx.y1 + 1, S.ny - 1), x1 = std::min(bx.x1 + 1, S.nx - 1);
  const Shape B{z1 - z0 + 1, y1 - y0 + 1, x1 - x0 + 1};
  Volume<uint8_t> mask(B);
  Volume<uint32_t> piece = Volume<uint32_t>::filled(B, 0u);
  uint8_t* V = mask.data();
  uint32_t* P = piece.data();
  auto global = [&](int64_t k, int64_t j, int64_t i) { return S.index(z0 + k, y0 + j, x0 + i); };
  for (int64_t k = 0; k < B.nz; ++k)
    for (int64_t j = 0; j < B.ny; ++j)
      for (int64_t i = 0; i < B.nx; ++i) V[B.index(k, j, i)] = L[global(k, j, i)] == l;
  uint32_t ids = 0;
  for (const Seed& sd : seeds) {
    const auto [k, j, i] = S.coords(sd.voxel);
    P[B.index(k - z0, j - y0, i - x0)] = sd.id;
    ids = std::max(ids, sd.id);
  }
  EdtOptions eo;
  eo.spacing = opt.spacing;
  Volume<float> dist;
  distance_transform(mask, dist, eo);
  watershed(dist, mask, piece, {false, 26, 4.0});
  std::vector<int64_t> size(size_t(ids) + 1, 0);
  for (int64_t q = 0; q < B.voxels(); ++q) ++size[P[q]];
  uint32_t main = 1;
  for (uint32_t m = 2; m <= ids; ++m)
    if (size[m] > size[main]) main = m;
  // The sheet between each piece and the largest: their voxels that touch
  // the other (6-neighbours), both sides, raw grey.
  std::vector<double> sheet_sum(size_t(ids) + 1, 0.0);
  std::vector<int64_t> sheet_n(size_t(ids) + 1, 0);
  const int64_t step[3] = {B.ny * B.nx, B.nx, 1};
  for (int64_t k = 0; k < B.nz; ++k)
    for (int64_t j = 0; j < B.ny; ++j)
      for (int64_t i = 0; i < B.nx; ++i) {
        const int64_t q = B.index(k, j, i);
        const uint32_t p = P[q];
        if (p == 0 || V[q] == 0) continue;
        const int64_t c[3] = {k, j, i}, n[3] = {B.nz, B.ny, B.nx};
        uint32_t other = 0;
        for (int ax = 0; ax < 3 && !other; ++ax)
          for (int d = -1; d <= 1 && !other; d += 2) {
            if (c[ax] + d < 0 || c[ax] + d >= n[ax]) continue;
            const uint32_t o = P[q + d * step[ax]];
            if (o && o != p && V[q + d * step[ax]] && (p == main || o == main)) other = o;
          }
        if (!other) continue;
        const uint32_t side = p == main ? other : p;
        sheet_sum[side] += G[global(k, j, i)];
        ++sheet_n[side];
      }
  const double height = opt.solid - opt.floor;
  std::vector<int32_t> ordinal(size_t(ids) + 1, 0);
  for (uint32_t m = 1; m <= ids; ++m) {
    if (m == main || size[m] < opt.min_piece_vox || sheet_n[m] == 0 || !(height > 0)) continue;
    const double dip = (opt.solid - sheet_sum[m] / double(sheet_n[m])) / height;
    if (dip >= min_dip) ordinal[m] = out.count++;
  }
  if (out.count < 2) return out;
  for (int64_t k = 0; k < B.nz; ++k)
    for (int64_t j = 0; j < B.ny; ++j)
      for (int64_t i = 0; i < B.nx; ++i) {
        const int64_t q = B.index(k, j, i);
        if (V[q] && ordinal[P[q]]) out.voxel.push_back(global(k, j, i)), out.piece.push_back(ordinal[P[q]]);
      }
  return out;
}

}  // namespace

namespace {

// How split_thin_pieces reads a label: at every stride-th voxel along each
// axis of its box, with these criteria.
struct ThinPass {
  int64_t stride = 1;
  double radius = 3, min_size = 27, max_share = 0.2, max_contact = 0.2;
  double min_size_at_face = 729;  // a piece touching a scan face: at least this many samples ((3 r)^3, set from r)
  bool screen = false;  // stop at the first piece (its voxels are not listed)
};

// Label l's voxels at every st-th voxel along each axis of its box, the box
// padded by one sample where the volume allows (a shell of void around the
// label, nearer to each of its voxels than anything beyond: the map
// measures within the label), and their distance to the void. Sample
// (k, j, i) is voxel (z0 + st k, y0 + st j, x0 + st i).
struct LabelSample {
  int64_t z0 = 0, y0 = 0, x0 = 0, st = 1;
  Shape B;
  Volume<uint8_t> mask;
  Volume<float> depth;
};
LabelSample sample_label(const Volume<uint32_t>& labels, uint32_t l, const LabelBox& bx,
                         const std::array<double, 3>& spacing, int64_t st) {
  LabelSample o;
  const Shape S = labels.shape();
  const uint32_t* L = labels.data();
  o.st = st;
  o.z0 = std::max<int64_t>(bx.z0 - st, 0), o.y0 = std::max<int64_t>(bx.y0 - st, 0),
  o.x0 = std::max<int64_t>(bx.x0 - st, 0);
  const int64_t z1 = std::min(bx.z1 + st, S.nz - 1), y1 = std::min(bx.y1 + st, S.ny - 1),
                x1 = std::min(bx.x1 + st, S.nx - 1);
  o.B = Shape{(z1 - o.z0) / st + 1, (y1 - o.y0) / st + 1, (x1 - o.x0) / st + 1};
  o.mask = Volume<uint8_t>(o.B);
  uint8_t* V = o.mask.data();
  for (int64_t k = 0; k < o.B.nz; ++k)
    for (int64_t j = 0; j < o.B.ny; ++j) {
      const uint32_t* row = L + S.index(o.z0 + st * k, o.y0 + st * j, o.x0);
      uint8_t* v = V + o.B.index(k, j, 0);
      for (int64_t i = 0; i < o.B.nx; ++i) v[i] = row[st * i] == l;
    }
  EdtOptions eo;
  for (size_t a = 0; a < 3; ++a) eo.spacing[a] = spacing[a] * double(st);
  distance_transform(o.mask, o.depth, eo);
  return o;
}

// Whether label l is thinner than 2 r throughout: no voxel deeper than r
// (merge_thin_walls takes such labels for pieces of a wall).
bool thin_throughout(const Volume<uint32_t>& labels, uint32_t l, const LabelBox& bx,
                     const std::array<double, 3>& spacing, double r) {
  const LabelSample ls = sample_label(labels, l, bx, spacing, 1);
  const float* D = ls.depth.data();
  for (int64_t q = 0; q < ls.B.voxels(); ++q)
    if (D[q] > r) return false;
  return true;
}

// Steps 1-2 of split_thin_pieces (header) for label l: the voxels that
// leave it, with their piece ordinal 1.. (with pass.screen: count 2 at the
// first piece found, no voxels; no_core where no voxel is deeper than the
// radius).
Pieces thin_pieces_one(const Volume<uint32_t>& labels, uint32_t l, const LabelBox& bx, const ThinPieceOptions& opt,
                       const ThinPass& pass) {
  Pieces out;
  const Shape S = labels.shape();
  const int64_t st = pass.stride;
  const double r = pass.radius;
  LabelSample ls = sample_label(labels, l, bx, opt.spacing, st);
  const int64_t z0 = ls.z0, y0 = ls.y0, x0 = ls.x0;
  const Shape B = ls.B;
  const int64_t nb = B.voxels();
  uint8_t* V = ls.mask.data();
  EdtOptions eo;
  for (size_t a = 0; a < 3; ++a) eo.spacing[a] = opt.spacing[a] * double(st);
  const Volume<float>& depth = ls.depth;
  // Step 1: the core (deeper than r) is void for the second map, which
  // then gives every other voxel its distance to the core.
  Volume<uint8_t> off_core(B);
  uint8_t* C = off_core.data();
  const float* D = depth.data();
  int64_t core = 0;
  for (int64_t q = 0; q < nb; ++q) {
    const bool c = V[q] && D[q] > r;
    C[q] = !c;
    core += c;
  }
  if (core == 0) {  // no part of the label deeper than r: nothing to hold a piece
    out.no_core = true;
    return out;
  }
  Volume<float> to_core;
  distance_transform(off_core, to_core, eo);
  const float* T = to_core.data();
  // V: 0 void, 1 the label's voxels the opening leaves (the residue), 2 in
  // the opening, 3 residue visited.
  int64_t voxels = 0;
  for (int64_t q = 0; q < nb; ++q) {
    voxels += V[q] != 0;
    if (V[q] && T[q] <= r) V[q] = 2;
  }
  // Step 2: the residue's 6-connected components.
  const int64_t step[3] = {B.ny * B.nx, B.nx, 1};
  std::vector<int64_t> stack, comp;
  int32_t pieces = 0;
  for (int64_t seed = 0; seed < nb; ++seed) {
    if (V[seed] != 1) continue;
    comp.clear();
    stack.assign(1, seed);
    V[seed] = 3;
    int64_t contact = 0;
    bool at_face = false;
    while (!stack.empty()) {
      const int64_t q = stack.back();
      stack.pop_back();
      comp.push_back(q);
      const int64_t c[3] = {q / step[0], (q / step[1]) % B.ny, q % B.nx};
      const int64_t g[3] = {z0 + st * c[0], y0 + st * c[1], x0 + st * c[2]}, n[3] = {S.nz, S.ny, S.nx},
                    bn[3] = {B.nz, B.ny, B.nx};
      bool touches = false;
      for (int ax = 0; ax < 3; ++ax) {
        if (g[ax] < st || g[ax] >= n[ax] - st) at_face = true;  // on the face (stride 1), or within a sample of it
        for (int d = -1; d <= 1; d += 2) {
          if (c[ax] + d < 0 || c[ax] + d >= bn[ax]) continue;
          const int64_t w = q + d * step[ax];
          if (V[w] == 2) touches = true;
          else if (V[w] == 1) V[w] = 3, stack.push_back(w);
        }
      }
      contact += touches;
    }
    const double size = double(comp.size());
    if ((at_face && size < pass.min_size_at_face) || size < pass.min_size || size > pass.max_share * double(voxels) ||
        double(contact) >= pass.max_contact * size)
      continue;
    ++pieces;
    if (pass.screen) break;
    for (const int64_t q : comp) {
      out.voxel.push_back(S.index(z0 + q / step[0], y0 + (q / step[1]) % B.ny, x0 + q % B.nx));
      out.piece.push_back(pieces);
    }
  }
  out.count = pieces + 1;
  return out;
}

}  // namespace

ThinPieceResult split_thin_pieces(Volume<uint32_t>& labels, uint32_t* count, const ThinPieceOptions& opt) {
  if (!(opt.radius_vox > 0) || !std::isfinite(opt.radius_vox))
    throw UsageError("segment: the thin-piece repair's radius must be > 0 voxels");
  ThinPieceResult res;
  const uint32_t n = *count;
  if (n == 0 || labels.shape().empty()) return res;
  const std::vector<LabelBox> box = label_boxes(labels, n);
  std::vector<Pieces> pieces(size_t(n) + 1);
  std::vector<uint8_t> wall(size_t(n) + 1, 0);
  const double face_floor = 27 * opt.radius_vox * opt.radius_vox * opt.radius_vox;  // (3 r)^3
  int64_t tested = 0, passed = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : tested, passed)
  for (int64_t l = 1; l <= int64_t(n); ++l) {
    const LabelBox& b = box[size_t(l)];
    const int64_t vmin =
        std::max<int64_t>(opt.min_piece_vox, int64_t(std::ceil(opt.min_piece_fraction * double(b.voxels))));
    if (double(vmin) > opt.max_share * double(b.voxels)) continue;  // no room for a piece beside a body
    const int64_t bv = (b.z1 - b.z0 + 1) * (b.y1 - b.y0 + 1) * (b.x1 - b.x0 + 1);
    if (bv > opt.max_box_vox) continue;
    ++tested;
    // Screen: the same on every second voxel along each axis (1/8 of the
    // maps' work), looser: a radius a voxel larger (a chip 5 voxels thick
    // has a sample 4 voxels deep on that grid), pieces of 1/24 the size
    // (thin pieces show few samples), up to half the label, touching the
    // opening by up to half their samples. On the dev scenes it sent to the
    // full test the labels that split and 2 more (of ~2 000), and lost none
    // of the full test's pieces; every third voxel lost 2 of 11 and saved
    // only half the time.
    ThinPass screen;
    screen.stride = 2, screen.radius = opt.radius_vox + 1, screen.screen = true;
    screen.min_size = std::max(4.0, double(vmin) / 24), screen.max_share = 0.5, screen.max_contact = 0.5;
    screen.min_size_at_face = face_floor / 24;
    const Pieces sc = thin_pieces_one(labels, uint32_t(l), b, opt, screen);
    ThinPass full;
    full.min_size_at_face = face_floor;
    full.radius = opt.radius_vox, full.min_size = double(vmin), full.max_share = opt.max_share,
    full.max_contact = opt.max_contact;
    if (sc.no_core) {  // thin throughout on the coarse grid: on the full one?
      wall[size_t(l)] = thin_throughout(labels, uint32_t(l), b, opt.spacing, opt.radius_vox);
      continue;
    }
    if (sc.count < 2) continue;
    ++passed;
    pieces[size_t(l)] = thin_pieces_one(labels, uint32_t(l), b, opt, full);
  }
  res.tested = tested;
  res.screened_in = passed;
  apply_pieces(labels.data(), pieces, n, count, "thin-piece repair", &res.split, &res.pieces_added);
  // The pieces are thinner than 2 r by construction (the opening left them).
  res.thin.assign(size_t(*count) + 1, 1);
  res.thin[0] = 0;
  auto as_box = [](const LabelBox& b) {
    return Box{b.z0, b.y0, b.x0, Shape{b.z1 - b.z0 + 1, b.y1 - b.y0 + 1, b.x1 - b.x0 + 1}};
  };
  for (uint32_t l = 1; l <= n; ++l) {
    res.thin[l] = wall[l];
    if (wall[l]) res.thin_boxes.push_back(as_box(box[l]));
  }
  // The pieces' boxes from their voxels, numbered as apply_pieces did.
  const Shape S = labels.shape();
  std::vector<LabelBox> added(size_t(*count - n) + 1);
  uint32_t next = n;
  for (uint32_t l = 1; l <= n; ++l) {
    const Pieces& p = pieces[l];
    if (p.count < 2) continue;
    for (size_t v = 0; v < p.voxel.size(); ++v) {
      const auto c = S.coords(p.voxel[v]);
      added[size_t(next - n) + size_t(p.piece[v])].add_run(c[0], c[1], c[2], c[2]);
    }
    next += uint32_t(p.count - 1);
  }
  for (size_t a = 1; a < added.size(); ++a) res.thin_boxes.push_back(as_box(added[a]));
  return res;
}

FaceCapResult split_face_caps(Volume<uint32_t>& labels, uint32_t* count, const Volume<uint8_t>& grey,
                              const FaceCapOptions& opt) {
  if (!(labels.shape() == grey.shape())) throw std::logic_error("split_face_caps: labels and grey differ in shape");
  FaceCapResult res;
  const uint32_t n = *count;
  const Shape S = labels.shape();
  if (n == 0 || S.empty()) return res;
  const uint32_t* L = labels.data();
  // Step 1 on every face, the footprints in parallel (each one's maxima
  // depend on it alone); a label's first candidate face (in the order of
  // opt.faces) gives its seeds.
  struct Task {
    Face f;
    uint32_t l;
    Box2 b;
  };
  std::vector<Task> tasks;
  for (int fi = 0; fi < 6; ++fi) {
    if (!opt.faces[size_t(fi)]) continue;
    Face f;
    f.a = fi / 2;
    const int64_t dims[3] = {S.nz, S.ny, S.nx};
    f.c = fi % 2 ? dims[f.a] - 1 : 0;
    f.nu = f.a == 0 ? S.ny : S.nz;
    f.nv = f.a == 2 ? S.ny : S.nx;
    std::map<uint32_t, Box2> boxes;
    for (int64_t u = 0; u < f.nu; ++u)
      for (int64_t v = 0; v < f.nv; ++v) {
        const uint32_t l = L[f.index(S, u, v)];
        if (!l) continue;
        Box2& b = boxes[l];
        b.u0 = std::min(b.u0, u), b.u1 = std::max(b.u1, u), b.v0 = std::min(b.v0, v), b.v1 = std::max(b.v1, v);
      }
    for (const auto& [l, b] : boxes) tasks.push_back({f, l, b});
  }
  std::vector<CapCandidate> found(tasks.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (int64_t t = 0; t < int64_t(tasks.size()); ++t) {
    const Task& k = tasks[size_t(t)];
    found[size_t(t)] = footprint_seeds(labels, grey, k.l, k.f, k.b, opt);
  }
  std::map<uint32_t, CapCandidate> candidate;
  for (size_t t = 0; t < tasks.size(); ++t)
    if (!found[t].seeds.empty() && !candidate.count(tasks[t].l)) candidate.emplace(tasks[t].l, std::move(found[t]));
  res.candidates = int64_t(candidate.size());
  if (candidate.empty()) return res;
  const std::vector<LabelBox> box = label_boxes(labels, n);
  uint32_t next = n;
  uint32_t* Lw = labels.data();
  for (const auto& [l, c] : candidate) {
    const LabelBox& b = box[l];
    const int64_t bv = (b.z1 - b.z0 + 1) * (b.y1 - b.y0 + 1) * (b.x1 - b.x0 + 1);
    if (bv > int64_t(1) << 28) continue;
    const Pieces p = split_cap(labels, grey, l, b, c.seeds, c.in_front ? opt.min_dip_in_front : opt.min_dip, opt);
    if (!renumber_pieces(Lw, p, next, "face-cap repair")) continue;
    ++res.split;
    res.pieces_added += p.count - 1;
  }
  *count = next;
  return res;
}

}  // namespace tg

#include "segmentation/watershed.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/errors.hpp"
#include "segmentation/neighbourhood.hpp"

namespace tg {
namespace {

// Flags in the label word while flooding; the label is in the low 29 bits.
constexpr uint32_t kQueued = 1u << 31;  // queued once (void voxels: pre-marked, never flooded)
constexpr uint32_t kLine = 1u << 30;    // line voxel (lines mode)
constexpr uint32_t kBorder = 1u << 29;  // on a face of the volume: neighbours need a bounds test
constexpr uint32_t kLabelMask = kBorder - 1;

void mark_border(const Shape& s, uint32_t* L) {
  auto row = [&](int64_t k, int64_t j) {
    uint32_t* r = L + s.index(k, j, 0);
    const bool whole = k == 0 || k + 1 == s.nz || j == 0 || j + 1 == s.ny;
    if (whole)
      for (int64_t i = 0; i < s.nx; ++i) r[i] |= kBorder;
    else {
      r[0] |= kBorder;
      r[s.nx - 1] |= kBorder;
    }
  };
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j) row(k, j);
}

// Stable counting sort of frontier entries by slice (z). Small batches are
// left as they are: they fit in cache anyway.
template <class Index>
class SliceSorter {
 public:
  explicit SliceSorter(const Shape& s)
      : slice_(s.slice_voxels()), inv_(1.0 / double(s.slice_voxels())), start_(size_t(s.nz) + 1) {}
  void sort(Index* first, Index* last) {
    const size_t m = size_t(last - first);
    if (m < 4096) return;
    std::fill(start_.begin(), start_.end(), 0);
    for (const Index* p = first; p != last; ++p) ++start_[size_t(slice(*p)) + 1];
    for (size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
    tmp_.resize(m);
    for (const Index* p = first; p != last; ++p) tmp_[size_t(start_[size_t(slice(*p))]++)] = *p;
    std::copy(tmp_.begin(), tmp_.end(), first);
  }

 private:
  int64_t slice(Index x) const {  // x / slice_ without a division per entry
    int64_t k = int64_t(double(x) * inv_);
    if (k * slice_ > int64_t(x)) --k;
    else if ((k + 1) * slice_ <= int64_t(x)) ++k;
    return k;
  }
  int64_t slice_;
  double inv_;
  std::vector<int64_t> start_;
  std::vector<Index> tmp_;
};

template <class Index>
void flood(const uint8_t* lev, uint32_t* L, const Shape& s, const seg::Neighbourhood& nb, bool lines) {
  const int64_t n = s.voxels();
  std::array<std::vector<Index>, 256> bucket;
  for (int64_t i = 0; i < n; ++i) {
    if (!lev[i]) {
      L[i] = (L[i] & kBorder) | kQueued;  // void: never queued, seen as "queued, unlabelled"
    } else if (L[i] & kLabelMask) {
      bucket[lev[i]].push_back(Index(i));
      L[i] |= kQueued;
    }
  }
  const int64_t sl = s.slice_voxels(), nx = s.nx;
#if defined(__SSE2__)
  // Interior voxels read their 3x3x3 block as nine rows of four labels
  // (the fourth lane is ignored) and decide without a branch per
  // neighbour: which neighbours are not yet queued, and whether the
  // labelled ones carry one label or several. The 26 data-dependent
  // branches of the scalar loop were mispredicted about half the time.
  // Bit b = 9 (dz+1) + 3 (dy+1) + (dx+1) of a block mask is neighbour (dz, dy, dx).
  std::array<int64_t, 9> row_off{};  // offset of lane 0 (dx = -1) of each row
  std::array<int64_t, 27> bit_off{};
  std::array<int, 27> bit_rank{};    // position of the neighbour in nb order (push order)
  uint32_t nb_bits = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy) {
      row_off[size_t(3 * (dz + 1) + dy + 1)] = dz * sl + dy * nx - 1;
      for (int dx = -1; dx <= 1; ++dx)
        bit_off[size_t(9 * (dz + 1) + 3 * (dy + 1) + dx + 1)] = dz * sl + dy * nx + dx;
    }
  for (int t = 0; t < nb.count; ++t) {
    const seg::Step st = nb.step[size_t(t)];
    const int b = 9 * (st.dz + 1) + 3 * (st.dy + 1) + st.dx + 1;
    nb_bits |= 1u << b;
    bit_rank[size_t(b)] = t;
  }
  // The last lane of the last row reads one label past x + sl + nx + 1.
  const int64_t simd_end = n - (sl + nx + 2);
  const __m128i label_mask = _mm_set1_epi32(int32_t(kLabelMask));
  const __m128i zero = _mm_setzero_si128(), big = _mm_set1_epi32(INT32_MAX);
  __m128i row_lanes[9];  // all-ones on the lanes that are neighbours
  for (int r = 0; r < 9; ++r)
    row_lanes[r] = _mm_set_epi32(0, (nb_bits >> (3 * r + 2)) & 1 ? -1 : 0,
                                         (nb_bits >> (3 * r + 1)) & 1 ? -1 : 0, (nb_bits >> (3 * r)) & 1 ? -1 : 0);
  auto vmax = [](__m128i a, __m128i b) {  // SSE2 has no pmaxsd; labels are < 2^29
    const __m128i gt = _mm_cmpgt_epi32(a, b);
    return _mm_or_si128(_mm_and_si128(gt, a), _mm_andnot_si128(gt, b));
  };
  auto vmin = [](__m128i a, __m128i b) {
    const __m128i gt = _mm_cmpgt_epi32(a, b);
    return _mm_or_si128(_mm_and_si128(gt, b), _mm_andnot_si128(gt, a));
  };
  auto hmax = [&](__m128i v) {
    v = vmax(v, _mm_shuffle_epi32(v, _MM_SHUFFLE(1, 0, 3, 2)));
    v = vmax(v, _mm_shuffle_epi32(v, _MM_SHUFFLE(2, 3, 0, 1)));
    return uint32_t(_mm_cvtsi128_si32(v));
  };
  auto hmin = [&](__m128i v) {
    v = vmin(v, _mm_shuffle_epi32(v, _MM_SHUFFLE(1, 0, 3, 2)));
    v = vmin(v, _mm_shuffle_epi32(v, _MM_SHUFFLE(2, 3, 0, 1)));
    return uint32_t(_mm_cvtsi128_si32(v));
  };
#endif
  // Visits the voxel x leaving the queue at level cur.
  auto visit = [&](const int64_t x, const int cur) {
    const uint32_t lx = L[x];
    const bool border = lx & kBorder;
    uint32_t seen = 0;
    bool line = false;
    int64_t cand[26];
    int nc = 0;
#if defined(__SSE2__)
    if (!border && x < simd_end) {
      __m128i hi = zero, lo = big;
      uint32_t free_bits = 0;
      for (int r = 0; r < 9; ++r) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(L + x + row_off[size_t(r)]));
        const __m128i queued = _mm_srai_epi32(v, 31);  // kQueued is the sign bit
        const __m128i lab = _mm_and_si128(v, label_mask);
        const __m128i labelled =
            _mm_andnot_si128(_mm_cmpeq_epi32(lab, zero), _mm_and_si128(queued, row_lanes[r]));
        hi = vmax(hi, _mm_and_si128(labelled, lab));
        lo = vmin(lo, _mm_or_si128(_mm_and_si128(labelled, lab), _mm_andnot_si128(labelled, big)));
        free_bits |= uint32_t(~_mm_movemask_ps(_mm_castsi128_ps(v)) & 7) << (3 * r);
      }
      free_bits &= nb_bits;
      seen = hmax(hi);
      line = seen != 0 && hmin(lo) != seen;
      // Candidates in nb order, as the scalar loop queues them (an
      // insertion sort of the few free neighbours by their rank).
      int rank[26];
      for (uint32_t m = free_bits; m; m &= m - 1) {
        const int b = __builtin_ctz(m);
        const int rk = bit_rank[size_t(b)];
        const int64_t y = x + bit_off[size_t(b)];
        __builtin_prefetch(lev + y);
        int c = nc++;
        for (; c > 0 && rank[c - 1] > rk; --c) {
          rank[c] = rank[c - 1];
          cand[c] = cand[c - 1];
        }
        rank[c] = rk;
        cand[c] = y;
      }
    } else
#endif
    {
      int64_t k = 0, j = 0, i = 0;
      if (border) {
        const auto c = s.coords(x);
        k = c[0], j = c[1], i = c[2];
      }
      // One pass over the neighbours: the labels they carry (lines mode)
      // and the ones not yet queued (solid by construction), which x will
      // queue if it is not a line.
      for (int t = 0; t < nb.count; ++t) {
        if (border) {
          const seg::Step st = nb.step[size_t(t)];
          if (!s.contains(k + st.dz, j + st.dy, i + st.dx)) continue;
        }
        const int64_t y = x + nb.offset[size_t(t)];
        const uint32_t ly = L[y];
        if (!(ly & kQueued)) {
          __builtin_prefetch(lev + y);  // its level is read below
          cand[nc++] = y;
          continue;
        }
        const uint32_t l = ly & kLabelMask;
        if (l == 0 || line) continue;
        if (seen == 0) seen = l;
        else if (l != seen) line = true;
      }
    }
    uint32_t lab = lx & kLabelMask;
    if (lab == 0) {
      // Lines mode only (without lines every queued voxel already has a
      // label): the label of the labelled neighbours, or a line if they
      // disagree (or, never expected, if none is labelled).
      if (line || seen == 0) {
        L[x] = lx | kLine;
        return;
      }
      lab = seen;
      L[x] = lx | lab;
    }
    const uint32_t push_label = lines ? 0u : lab;
    for (int c = 0; c < nc; ++c) {
      const int64_t y = cand[c];
      L[y] = (L[y] & kBorder) | kQueued | push_label;
      bucket[size_t(std::min<int>(lev[y], cur))].push_back(Index(y));
    }
  };
  SliceSorter<Index> sorter(s);
  // Software prefetch of the 3x3 rows around the voxel kAhead places down
  // the queue, labels and levels: the hardware cannot guess these addresses.
  constexpr size_t kAhead = 12;
  const std::array<int64_t, 9> rows = {-sl - nx - 1, -sl - 1, -sl + nx - 1, -nx - 1, -1,
                                       nx - 1,       sl - nx - 1, sl - 1, sl + nx - 1};
  // Integer addresses: next to a border the row may lie outside the volume,
  // where a prefetch is harmless but pointer arithmetic would not be.
  const auto Lbase = reinterpret_cast<uintptr_t>(L), lbase = reinterpret_cast<uintptr_t>(lev);
  for (int cur = 255; cur >= 1; --cur) {
    auto& b = bucket[size_t(cur)];
    // Breadth-first rounds: the voxels queued at this level so far, then
    // those they queue at this level, and so on (within a level, voxels
    // leave in order of geodesic distance, as with one FIFO). Each round is
    // put in slice order first, so the flood sweeps the volume instead of
    // jumping around it: the loop is bound by cache misses on the labels.
    // Measured on a 256^3 scan (10 M solid voxels, one core): 2.4 s in plain
    // FIFO order, 1.7 s in slice order, 0.95 s with the prefetch. (Deciding
    // each round from the rounds before it would let threads share a round,
    // but then two neighbours of one round can take different labels, and
    // the rule that makes one of them a line doubled the time on one core
    // and thickened the lines: median grain volume error -1.1 % instead of
    // -1.0 %. Tried and dropped.)
    for (size_t head = 0; head < b.size();) {
      const size_t end = b.size();
      sorter.sort(b.data() + head, b.data() + end);
      for (; head < end; ++head) {
        if (head + kAhead < end) {
          const uintptr_t z = uintptr_t(b[head + kAhead]);
          for (int64_t o : rows) {
            __builtin_prefetch(reinterpret_cast<const void*>(Lbase + (z + uintptr_t(o)) * sizeof(uint32_t)));
            __builtin_prefetch(reinterpret_cast<const void*>(lbase + (z + uintptr_t(o))));
          }
        }
        visit(int64_t(b[head]), cur);
      }
    }
    std::vector<Index>().swap(b);  // free this level's memory now
  }
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) L[i] = (L[i] & kLine) ? 0u : (L[i] & kLabelMask);
}

}  // namespace

double quantise_levels(const Volume<float>& dist, Volume<uint8_t>& solid, double buckets_per_unit) {
  if (dist.shape() != solid.shape())
    throw UsageError("watershed: distance " + dist.shape().str() + " and mask " + solid.shape().str() +
                     " must have one shape");
  if (!(buckets_per_unit > 0) || !std::isfinite(buckets_per_unit))
    throw UsageError("watershed: buckets per distance unit must be positive");
  const int64_t n = solid.size();
  const float* d = dist.data();
  uint8_t* m = solid.data();
  float dmax = 0;
  bool finite = true;
#pragma omp parallel for schedule(static) reduction(max : dmax) reduction(&& : finite)
  for (int64_t i = 0; i < n; ++i)
    if (m[i]) {
      finite = finite && std::isfinite(d[i]) && d[i] >= 0;
      dmax = std::max(dmax, d[i]);
    }
  if (!finite) throw UsageError("watershed: the distance map is not finite on the solid");
  double q = buckets_per_unit;
  if (double(dmax) * q >= 255.0) q = 254.0 / double(dmax);
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
    if (m[i]) m[i] = uint8_t(1 + std::min(254, int(double(d[i]) * q)));
  return q;
}

void watershed_levels(const Volume<uint8_t>& levels, Volume<uint32_t>& labels, const WatershedOptions& opt) {
  const Shape s = levels.shape();
  if (labels.shape() != s)
    throw UsageError("watershed: levels " + s.str() + " and markers " + labels.shape().str() + " must have one shape");
  const seg::Neighbourhood nb(s, opt.connectivity);
  const int64_t n = levels.size();
  uint32_t* L = labels.data();
  bool ok = true;
#pragma omp parallel for schedule(static) reduction(&& : ok)
  for (int64_t i = 0; i < n; ++i) ok = ok && L[i] < kLabelMask;
  if (!ok) throw UsageError("watershed: marker labels must be below 2^29 - 1");
  if (s.empty()) return;
  mark_border(s, L);
  if (n <= int64_t(UINT32_MAX)) flood<uint32_t>(levels.data(), L, s, nb, opt.lines);
  else flood<int64_t>(levels.data(), L, s, nb, opt.lines);
}

double watershed(const Volume<float>& dist, const Volume<uint8_t>& solid, Volume<uint32_t>& labels,
                 const WatershedOptions& opt) {
  if (dist.shape() != solid.shape() || labels.shape() != solid.shape())
    throw UsageError("watershed: distance " + dist.shape().str() + ", mask " + solid.shape().str() +
                     " and markers " + labels.shape().str() + " must have one shape");
  Volume<uint8_t> lev = solid.clone();
  const double q = quantise_levels(dist, lev, opt.buckets_per_unit);
  watershed_levels(lev, labels, opt);
  return q;
}

}  // namespace tg

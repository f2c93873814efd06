#include "segmentation/watershed.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/errors.hpp"
#include "segmentation/neighbourhood.hpp"

namespace tg {
namespace {

constexpr uint32_t kQueued = 1u << 31;
constexpr uint32_t kLine = 1u << 30;  // line voxel while flooding (label bits all 0 besides this)
constexpr uint32_t kLabelMask = kLine - 1;

}  // namespace

void watershed(const Volume<float>& dist, const Volume<uint8_t>& solid, Volume<uint32_t>& labels,
               const WatershedOptions& opt) {
  const Shape s = solid.shape();
  if (dist.shape() != s || labels.shape() != s)
    throw UsageError("watershed: distance " + dist.shape().str() + ", mask " + s.str() + " and markers " +
                     labels.shape().str() + " must have one shape");
  if (!(opt.buckets_per_unit > 0) || !std::isfinite(opt.buckets_per_unit))
    throw UsageError("watershed: buckets per distance unit must be positive");
  const seg::Neighbourhood nb(s, opt.connectivity);
  const int64_t n = solid.size();
  const float* d = dist.data();
  const uint8_t* m = solid.data();
  uint32_t* L = labels.data();

  // Levels and validation of the markers.
  float dmax = 0;
  for (int64_t i = 0; i < n; ++i) {
    if (!m[i]) continue;
    if (!std::isfinite(d[i])) throw UsageError("watershed: the distance map is not finite on the solid");
    dmax = std::max(dmax, d[i]);
    if (L[i] > kLabelMask - 1) throw UsageError("watershed: marker labels must be below 2^30 - 1");
  }
  const double q = opt.buckets_per_unit;
  auto level = [&](int64_t i) { return static_cast<int64_t>(double(d[i]) * q); };
  const int64_t nlev = static_cast<int64_t>(double(dmax) * q) + 1;
  std::vector<std::vector<int64_t>> bucket(static_cast<size_t>(nlev));

  for (int64_t i = 0; i < n; ++i)
    if (L[i]) {
      if (!m[i]) L[i] = 0;  // a marker on void seeds nothing
      else {
        bucket[size_t(level(i))].push_back(i);
        L[i] |= kQueued;
      }
    }

  for (int64_t cur = nlev - 1; cur >= 0; --cur) {
    auto& b = bucket[size_t(cur)];
    for (size_t head = 0; head < b.size(); ++head) {
      const int64_t x = b[head];
      const auto [k, j, i] = s.coords(x);
      const bool in = seg::interior(s, k, j, i);
      // One pass over the neighbours: the labels they carry (lines mode) and
      // the solid ones not yet queued, which x will queue if it is not a line.
      uint32_t lab = L[x] & kLabelMask, seen = 0;
      bool line = false;
      int64_t cand[26];
      int nc = 0;
      for (int t = 0; t < nb.count; ++t) {
        if (!in) {
          const seg::Step st = nb.step[size_t(t)];
          if (!s.contains(k + st.dz, j + st.dy, i + st.dx)) continue;
        }
        const int64_t y = x + nb.offset[size_t(t)];
        const uint32_t ly = L[y];
        if (!(ly & kQueued)) {
          if (m[y]) cand[nc++] = y;
          continue;
        }
        const uint32_t l = ly & kLabelMask;
        if (l == 0 || line) continue;
        if (seen == 0) seen = l;
        else if (l != seen) line = true;
      }
      if (lab == 0) {
        // Lines mode only (without lines every queued voxel already has a
        // label): the label of the labelled neighbours, or a line if they
        // disagree (or, never expected, if none is labelled).
        if (line || seen == 0) {
          L[x] |= kLine;
          continue;
        }
        lab = seen;
        L[x] = kQueued | lab;
      }
      for (int c = 0; c < nc; ++c) {
        const int64_t y = cand[c];
        L[y] = kQueued | (opt.lines ? 0u : lab);
        bucket[size_t(std::min(level(y), cur))].push_back(y);
      }
    }
    std::vector<int64_t>().swap(b);  // free this level's memory now
  }
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) L[i] = (L[i] & kLine) ? 0u : (L[i] & kLabelMask);
}

}  // namespace tg

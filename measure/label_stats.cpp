#include "measure/label_stats.hpp"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_set>

#include "core/errors.hpp"

namespace tg::measure {
namespace {

// Label -> dense index. A direct table when the largest label is modest
// (<= 2^24 entries, 64 MB at most), else binary search in the sorted label
// list; both behind a one-entry cache, since labels come in runs along x.
class LabelIndex {
 public:
  explicit LabelIndex(std::vector<uint32_t> sorted) : labels_(std::move(sorted)) {
    const uint32_t top = labels_.empty() ? 0 : labels_.back();
    if (top <= (1u << 24)) {
      table_.assign(static_cast<size_t>(top) + 1, -1);
      for (size_t n = 0; n < labels_.size(); ++n) table_[labels_[n]] = static_cast<int32_t>(n);
    }
  }
  int32_t operator()(uint32_t label) const {
    if (!table_.empty()) return table_[label];
    auto it = std::lower_bound(labels_.begin(), labels_.end(), label);
    return static_cast<int32_t>(it - labels_.begin());
  }
  const std::vector<uint32_t>& labels() const { return labels_; }

 private:
  std::vector<uint32_t> labels_;
  std::vector<int32_t> table_;
};

// Slices [z0, z1) of thread t out of nt in the core [c0, c1): contiguous, in thread order.
std::pair<int64_t, int64_t> slab(int64_t c0, int64_t c1, int t, int nt) {
  const int64_t m = c1 - c0;
  return {c0 + m * t / nt, c0 + m * (t + 1) / nt};
}

std::vector<uint32_t> distinct_labels(const VolumeView<const uint32_t>& v, int64_t c0, int64_t c1, int nt) {
  const Shape s = v.shape();
  std::vector<std::vector<uint32_t>> found(static_cast<size_t>(nt));
#pragma omp parallel num_threads(nt)
  {
    const int t = omp_get_thread_num();
    const int n = omp_get_num_threads();
    std::unordered_set<uint32_t> seen;
    uint32_t last = 0;
    auto [z0, z1] = slab(c0, c1, t, n);
    for (int64_t k = z0; k < z1; ++k)
      for (int64_t j = 0; j < s.ny; ++j)
        for (uint32_t l : v.row(k, j))
          if (l != last) {
            last = l;
            if (l) seen.insert(l);
          }
    found[static_cast<size_t>(t)].assign(seen.begin(), seen.end());
  }
  std::vector<uint32_t> all;
  for (auto& f : found) all.insert(all.end(), f.begin(), f.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

}  // namespace

void LabelMoments::merge(const LabelMoments& o) {
  n += o.n; sk += o.sk; sj += o.sj; si += o.si;
  skk += o.skk; sjj += o.sjj; sii += o.sii; skj += o.skj; ski += o.ski; sji += o.sji;
  for (int a = 0; a < 3; ++a) { lo[a] = std::min(lo[a], o.lo[a]); hi[a] = std::max(hi[a], o.hi[a]); }
  border = border || o.border;
}

LabelStatsResult label_stats(const VolumeView<const uint32_t>& v, const LabelStatsOptions& opt) {
  if (!v.geometry().has_voxel_size()) throw UsageError("label_stats: the label volume has no voxel size (give --voxel-um)");
  return label_stats_from_sums(label_sums(v, 0, v.shape().nz, 0, opt), v.geometry(), opt);
}

LabelSums label_sums(const VolumeView<const uint32_t>& v, int64_t c0, int64_t c1, int64_t k_offset,
                     const LabelStatsOptions& opt) {
  if (opt.threads < 0) throw UsageError("label_stats: threads must be >= 0");
  const Shape s = v.shape();
  if (c0 < 0 || c1 > s.nz || c0 > c1 || k_offset < 0)
    throw UsageError("label_sums: core slices [" + std::to_string(c0) + ", " + std::to_string(c1) +
                     ") outside the window " + s.str());
  // Sums of squared indices must fit int64: n * max_index^2 < 2^63 (the
  // whole volume's extent: the sums of every slab add up).
  const double big = static_cast<double>(std::max({s.nz + k_offset, s.ny, s.nx}));
  if (big * big * static_cast<double>(s.nz + k_offset) * static_cast<double>(s.slice_voxels()) > 9.0e18)
    throw ResourceError("label_stats: volume " + s.str() + " too large for 64-bit moment sums");
  const int nt = opt.threads > 0 ? opt.threads : omp_get_max_threads();

  const LabelIndex index(distinct_labels(v, c0, c1, nt));
  const size_t nl = index.labels().size();

  struct Partial {
    std::vector<LabelMoments> acc;
    std::vector<std::pair<int32_t, SurfaceVoxel>> surface;
  };
  std::vector<Partial> part(static_cast<size_t>(nt));

#pragma omp parallel num_threads(nt)
  {
    const int t = omp_get_thread_num();
    const int n_threads = omp_get_num_threads();
    Partial& P = part[static_cast<size_t>(t)];
    P.acc.assign(nl, LabelMoments{});
    auto [z0, z1] = slab(c0, c1, t, n_threads);
    uint32_t last = 0;
    int32_t last_idx = -1;
    // Sum of i^2 for i in [0, m): the moments of a run of one label in a row
    // in closed form (runs are tens of voxels long: the per-voxel sums were
    // most of this pass).
    auto squares_below = [](int64_t m) { return (m - 1) * m * (2 * m - 1) / 6; };
    for (int64_t kw = z0; kw < z1; ++kw)
      for (int64_t j = 0; j < s.ny; ++j) {
        const int64_t k = kw + k_offset;  // the whole volume's index
        const uint32_t* row = v.row(kw, j).data();
        // The window holds the slices next to the core, or the core ends at
        // the volume's face: no slice there in the window = none in the volume.
        const uint32_t* below = kw > 0 ? v.row(kw - 1, j).data() : nullptr;
        const uint32_t* above = kw + 1 < s.nz ? v.row(kw + 1, j).data() : nullptr;
        const uint32_t* before = j > 0 ? v.row(kw, j - 1).data() : nullptr;
        const uint32_t* after = j + 1 < s.ny ? v.row(kw, j + 1).data() : nullptr;
        for (int64_t i0 = 0; i0 < s.nx;) {
          const uint32_t l = row[i0];
          int64_t i1 = i0 + 1;
          while (i1 < s.nx && row[i1] == l) ++i1;
          if (!l) {
            i0 = i1;
            continue;
          }
          if (l != last) { last = l; last_idx = index(l); }
          LabelMoments& a = P.acc[static_cast<size_t>(last_idx)];
          const int64_t len = i1 - i0;
          const int64_t s1 = (i0 + i1 - 1) * len / 2, s2 = squares_below(i1) - squares_below(i0);
          a.n += len;
          a.sk += k * len; a.sj += j * len; a.si += s1;
          a.skk += k * k * len; a.sjj += j * j * len; a.sii += s2;
          a.skj += k * j * len; a.ski += k * s1; a.sji += j * s1;
          a.lo = {std::min(a.lo[0], k), std::min(a.lo[1], j), std::min(a.lo[2], i0)};
          a.hi = {std::max(a.hi[0], k + 1), std::max(a.hi[1], j + 1), std::max(a.hi[2], i1)};
          const bool edge = !below || !above || j == 0 || i0 == 0 || j == s.ny - 1 || i1 == s.nx;
          a.border = a.border || edge;
          if (opt.collect_surface) {
            for (int64_t i = i0; i < i1; ++i) {
              // Exposed faces: -z, +z, -y, +y, -x, +x (bits 0..5).
              uint8_t m = 0;
              if (!below || below[i] != l) m |= 1;
              if (!above || above[i] != l) m |= 2;
              if (!before || before[i] != l) m |= 4;
              if (!after || after[i] != l) m |= 8;
              if (i == i0) m |= 16;      // the run starts: another label, void or the volume's face
              if (i == i1 - 1) m |= 32;  // likewise where it ends
              if (m) P.surface.push_back({last_idx, SurfaceVoxel{static_cast<int32_t>(k), static_cast<int32_t>(j),
                                                                 static_cast<int32_t>(i), m}});
            }
          }
          i0 = i1;
        }
      }
  }

  // Merge in thread order.
  LabelSums r;
  r.labels = index.labels();
  r.moments.assign(nl, LabelMoments{});
  for (const auto& P : part)  // a thread the runtime did not start left its partial empty
    for (size_t n = 0; n < P.acc.size(); ++n) r.moments[n].merge(P.acc[n]);
  r.surface_offset.assign(nl + 1, 0);
  if (opt.collect_surface) {
    for (const auto& P : part)
      for (const auto& [idx, sv] : P.surface) ++r.surface_offset[static_cast<size_t>(idx) + 1];
    for (size_t n = 0; n < nl; ++n) r.surface_offset[n + 1] += r.surface_offset[n];
    r.surface.resize(static_cast<size_t>(r.surface_offset[nl]));
    std::vector<int64_t> fill(r.surface_offset.begin(), r.surface_offset.end() - 1);
    for (const auto& P : part)  // thread order = slab order = serial scan order
      for (const auto& [idx, sv] : P.surface) r.surface[static_cast<size_t>(fill[static_cast<size_t>(idx)]++)] = sv;
  }
  return r;
}

LabelStatsResult label_stats_from_sums(LabelSums sums, const Geometry& g, const LabelStatsOptions& opt) {
  if (!g.has_voxel_size()) throw UsageError("label_stats: the label volume has no voxel size (give --voxel-um)");
  const size_t nl = sums.labels.size();
  LabelStatsResult r;
  r.labels.resize(nl);
  r.surface_offset = std::move(sums.surface_offset);
  r.surface = std::move(sums.surface);
  const auto& h = g.voxel_size_m;
  const double dv = h[0] * h[1] * h[2];
  for (size_t n = 0; n < nl; ++n) {
    const LabelMoments& a = sums.moments[n];
    LabelStats& st = r.labels[n];
    st.label = sums.labels[n];
    st.voxels = a.n;
    st.volume_m3 = static_cast<double>(a.n) * dv;
    const double inv = 1.0 / static_cast<double>(a.n);
    const Eigen::Vector3d mean(a.sk * inv, a.sj * inv, a.si * inv);
    for (int c = 0; c < 3; ++c) st.centroid_m[c] = g.origin_m[c] + (mean[c] + 0.5) * h[c];
    st.box_lo = a.lo;
    st.box_hi = a.hi;
    // Covariance of voxel indices, then scaled to metres; + the cube's own h^2/12.
    Eigen::Matrix3d cov;
    cov(0, 0) = a.skk * inv - mean[0] * mean[0];
    cov(1, 1) = a.sjj * inv - mean[1] * mean[1];
    cov(2, 2) = a.sii * inv - mean[2] * mean[2];
    cov(0, 1) = cov(1, 0) = a.skj * inv - mean[0] * mean[1];
    cov(0, 2) = cov(2, 0) = a.ski * inv - mean[0] * mean[2];
    cov(1, 2) = cov(2, 1) = a.sji * inv - mean[1] * mean[2];
    const Eigen::Vector3d hv(h[0], h[1], h[2]);
    Eigen::Matrix3d C = hv.asDiagonal() * cov * hv.asDiagonal();
    for (int c = 0; c < 3; ++c) C(c, c) += h[c] * h[c] / 12.0;
    {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ev(C);  // ascending
      for (int c = 0; c < 3; ++c) {
        st.ellipsoid_semi_axes_m[c] = std::sqrt(5.0 * std::max(0.0, ev.eigenvalues()[2 - c]));
        st.ellipsoid_axes.col(c) = ev.eigenvectors().col(2 - c);
      }
    }
    C *= st.volume_m3;
    st.inertia_m5 = C.trace() * Eigen::Matrix3d::Identity() - C;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(st.inertia_m5);
    st.principal_moments_m5 = es.eigenvalues();
    st.principal_axes = es.eigenvectors();
    st.d_eq_m = std::cbrt(6.0 * st.volume_m3 / std::numbers::pi);
    st.touches_border = a.border;
    st.below_limit = st.d_eq_m < opt.detection_limit_m;
  }
  return r;
}

}  // namespace tg::measure

#include "track/registration.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace tg::track {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

bool similar_volume(double va, double vb, double ratio) { return vb <= va * ratio && va <= vb * ratio; }

// Least-squares affine y = M x + t through pairs (a[i], b[j]); false when singular.
bool fit_affine(const std::vector<Point>& a, const std::vector<Point>& b, const std::vector<std::pair<int, int>>& pairs,
                StageMap& m) {
  if (pairs.size() < 4) return false;
  Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
  Eigen::Matrix<double, 4, 3> aty = Eigen::Matrix<double, 4, 3>::Zero();
  for (const auto& [i, j] : pairs) {
    const Eigen::Vector4d x(a[i].c[0], a[i].c[1], a[i].c[2], 1.0);
    const Eigen::Vector3d y(b[j].c[0], b[j].c[1], b[j].c[2]);
    ata += x * x.transpose();
    aty += x * y.transpose();
  }
  Eigen::LDLT<Eigen::Matrix4d> ldlt(ata);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-12) return false;
  const Eigen::Matrix<double, 4, 3> sol = ldlt.solve(aty);
  m.M = sol.topRows<3>().transpose();
  m.t = sol.row(3).transpose();
  double ss = 0;
  for (const auto& [i, j] : pairs) ss += (m.apply(a[i].c) - Eigen::Vector3d(b[j].c[0], b[j].c[1], b[j].c[2])).squaredNorm();
  m.rms_vox = std::sqrt(ss / static_cast<double>(pairs.size()));
  m.matches = static_cast<int>(pairs.size());
  return true;
}

// Mutual nearest pairs under the map, within `thr` and of similar volume.
std::vector<std::pair<int, int>> mutual_pairs(const std::vector<Point>& a, const std::vector<Point>& b,
                                              const StageMap& m, double thr, double ratio) {
  const int na = static_cast<int>(a.size()), nb = static_cast<int>(b.size());
  std::vector<int> best_b(na, -1), best_a(nb, -1);
  std::vector<double> db(na, thr * thr), da(nb, thr * thr);
  for (int i = 0; i < na; ++i) {
    const Eigen::Vector3d p = m.apply(a[i].c);
    for (int j = 0; j < nb; ++j) {
      if (!similar_volume(a[i].volume, b[j].volume, ratio)) continue;
      const double d2 = (p - Eigen::Vector3d(b[j].c[0], b[j].c[1], b[j].c[2])).squaredNorm();
      if (d2 < db[i]) db[i] = d2, best_b[i] = j;
      if (d2 < da[j]) da[j] = d2, best_a[j] = i;
    }
  }
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < na; ++i)
    if (best_b[i] >= 0 && best_a[best_b[i]] == i) out.emplace_back(i, best_b[i]);
  return out;
}

// Where a particle of stage A is looked for in stage B, sideways: turned by
// an angle about the scan's axis (through (cy, cx)) and shifted by (oy, ox).
struct Prior {
  double cos = 1, sin = 0, cy = 0, cx = 0, oy = 0, ox = 0;
  std::array<double, 2> yx(const Point& p) const {
    const double y = p.c[1] - cy, x = p.c[2] - cx;
    return {cy + cos * y - sin * x + oy, cx + sin * y + cos * x + ox};
  }
};

// The specimen's common sideways offset between the stages once A is turned
// by `pr`'s angle: the mode of the offsets of all grain-sized pairs of
// similar volume within the axial window, voted in bins of `bin` voxels
// sideways and `bin_z` along the axis (a bin and its 26 neighbours; the mean
// sideways offset of their pairs). The axial bins keep the floor of chance
// pairs low; the compression spreads the true pairs over a few of them.
// Returns the pairs at the mode and, in `pr`, its offset; `at_zero` gets
// the pairs around a zero offset.
double vote_offset(const std::vector<Point>& a, const std::vector<Point>& b, double v_med, double axial, double bin,
                   double bin_z, double ratio, Prior& pr, double& at_zero, double max_offset = 0) {
  using Key = std::array<int64_t, 3>;
  std::map<Key, std::array<double, 3>> votes;  // bin -> (count, sum dy, sum dx)
  pr.oy = pr.ox = 0;
  for (const Point& pa : a) {
    if (pa.volume < 0.3 * v_med) continue;
    const auto q = pr.yx(pa);
    for (const Point& pb : b) {
      if (pb.volume < 0.3 * v_med || !similar_volume(pa.volume, pb.volume, ratio)) continue;
      const double dz = pb.c[0] - pa.c[0];
      if (std::abs(dz) > axial) continue;
      const double dy = pb.c[1] - q[0], dx = pb.c[2] - q[1];
      if (max_offset > 0 && dy * dy + dx * dx > max_offset * max_offset) continue;
      auto& v = votes[{std::llround(dz / bin_z), std::llround(dy / bin), std::llround(dx / bin)}];
      v[0] += 1, v[1] += dy, v[2] += dx;
    }
  }
  auto around = [&](const Key& k) {
    std::array<double, 3> t{0, 0, 0};
    for (int64_t u = -1; u <= 1; ++u)
      for (int64_t v = -1; v <= 1; ++v)
        for (int64_t w = -1; w <= 1; ++w)
          if (auto it = votes.find({k[0] + u, k[1] + v, k[2] + w}); it != votes.end())
            for (int c = 0; c < 3; ++c) t[c] += it->second[c];
    return t;
  };
  // The window's best is at or next to one of the fullest bins: only the 16
  // fullest are tried (std::map's order and a stable sort: ties resolve the
  // same way every run).
  std::vector<std::pair<double, Key>> full;
  full.reserve(votes.size());
  at_zero = 0;
  for (const auto& [k, v] : votes) {
    full.emplace_back(v[0], k);
    if (k[1] == 0 && k[2] == 0) at_zero = std::max(at_zero, around(k)[0]);  // no sideways offset, any axial one
  }
  const size_t top = std::min<size_t>(16, full.size());
  std::partial_sort(full.begin(), full.begin() + std::ptrdiff_t(top), full.end(),
                    [](const auto& x, const auto& y) { return x.first > y.first || (x.first == y.first && x.second < y.second); });
  std::array<double, 3> best{0, 0, 0};
  for (size_t q = 0; q < top; ++q) {
    const auto t = around(full[q].second);
    if (t[0] > best[0]) best = t;
  }
  if (best[0] > 0) pr.oy = best[1] / best[0], pr.ox = best[2] / best[0];
  return best[0];
}

// The sideways prior of step 0 (registration.hpp).
Prior sideways_prior(const std::vector<Point>& a, const std::vector<Point>& b, double v_med, double axial, double bin,
                     double bin_z, double ratio, int min_matches, double cy, double cx, double fov_radius) {
  Prior pr;
  pr.cy = cy, pr.cx = cx;
  double at_zero = 0;
  const double n = vote_offset(a, b, v_med, axial, bin, bin_z, ratio, pr, at_zero);
  // An offset only where it clearly beats none: a series that does not
  // shift keeps (0, 0) and the map it had.
  if (n < std::max<double>(min_matches, 1.25 * at_zero)) pr.oy = pr.ox = 0;
  const double kept = pr.oy == 0 && pr.ox == 0 ? at_zero : n;
  std::vector<Point> grains;
  for (const Point& p : a)
    if (p.volume >= 0.3 * v_med) grains.push_back(p);
  if (kept >= 0.25 * double(grains.size()) || fov_radius <= 0) return pr;
  // Few pairs agree: perhaps the specimen was turned about its axis. Angles
  // in steps that move the scan's rim by half a bin, each voted with up to
  // 100 of A's grains (evenly spread through its list) and offsets within a
  // quarter of the scan's radius, so that the search costs ~angles x 100 x nB
  // distance checks; the best angle is kept when it gathers half as many
  // pairs again as no turn does on the same terms.
  std::vector<Point> some;
  const size_t every = std::max<size_t>(1, grains.size() / 100);
  for (size_t i = 0; i < grains.size(); i += every) some.push_back(grains[i]);
  const double step = std::min(0.5 * bin / fov_radius, std::numbers::pi / 36);
  const double reach = 0.25 * fov_radius;
  Prior best = pr;
  best.oy = best.ox = 0;
  double z0 = 0;
  const double unturned = vote_offset(some, b, v_med, axial, bin, bin_z, ratio, best, z0, reach);
  double best_n = unturned;
  for (double t = step; t < 2 * std::numbers::pi - 0.5 * step; t += step) {
    Prior q = pr;
    q.cos = std::cos(t), q.sin = std::sin(t);
    const double m = vote_offset(some, b, v_med, axial, bin, bin_z, ratio, q, z0, reach);
    if (m > best_n) best_n = m, best = q;
  }
  return best_n >= std::max<double>(min_matches, 1.5 * unturned) && best.sin != 0 ? best : pr;
}

}  // namespace

StageMap estimate_map(const std::vector<Point>& a, const std::vector<Point>& b, double z_extent_vox,
                      const MapOptions& o) {
  StageMap fallback;
  fallback.method = a.empty() || b.empty() ? "identity" : "fallback";
  const double e = o.fallback_strain;
  fallback.M(0, 0) = 1 - e;
  fallback.t(0) = e * o.fixed_plane_vox;
  if (a.empty() || b.empty()) return fallback;

  std::vector<double> vols;
  for (const Point& p : a) vols.push_back(p.volume);
  for (const Point& p : b) vols.push_back(p.volume);
  const double v_med = median(vols), r_med = r_eq(v_med);
  const double lateral = o.lateral_radius_vox > 0 ? o.lateral_radius_vox : std::max(3.0, 0.5 * r_med);
  const double axial = o.max_axial_vox > 0 ? o.max_axial_vox : 0.25 * z_extent_vox;
  const double thr = o.ransac_threshold_vox > 0 ? o.ransac_threshold_vox : std::max(1.5, 0.3 * r_med);

  // 0. A sideways offset of the whole specimen (remounted, recentred) larger
  // than the lateral radius would leave no candidate pair: vote for it.
  double cy = 0, cx = 0, fov = 0;  // the scan's axis and radius, from the particles of both stages
  {
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (const auto* s : {&a, &b})
      for (const Point& p : *s)
        for (int d = 0; d < 2; ++d) lo[d] = std::min(lo[d], p.c[1 + d]), hi[d] = std::max(hi[d], p.c[1 + d]);
    cy = 0.5 * (lo[0] + hi[0]), cx = 0.5 * (lo[1] + hi[1]);
    fov = 0.5 * std::hypot(hi[0] - lo[0], hi[1] - lo[1]);
  }
  // Bins: the RANSAC threshold sideways; along the axis at least 2 % of the
  // extent, so a strain increment of up to ~6 % spreads its pairs over the
  // three bins a window holds.
  const Prior prior = sideways_prior(a, b, v_med, axial, thr, std::max(thr, 0.02 * z_extent_vox), o.volume_ratio,
                                     o.min_matches, cy, cx, fov);

  // 1. Candidate pairs: grain-sized A particles, B particles beside them in (y, x).
  std::vector<cv::Point3f> src, dst;
  std::vector<std::pair<int, int>> cand;
  std::vector<std::pair<double, int>> near;
  for (int i = 0; i < static_cast<int>(a.size()); ++i) {
    if (a[i].volume < 0.3 * v_med) continue;
    const std::array<double, 2> at = prior.yx(a[i]);
    near.clear();
    for (int j = 0; j < static_cast<int>(b.size()); ++j) {
      if (!similar_volume(a[i].volume, b[j].volume, o.volume_ratio)) continue;
      if (std::abs(b[j].c[0] - a[i].c[0]) > axial) continue;
      const double dy = b[j].c[1] - at[0], dx = b[j].c[2] - at[1];
      const double d2 = dy * dy + dx * dx;
      if (d2 <= lateral * lateral) near.emplace_back(d2, j);
    }
    std::sort(near.begin(), near.end());
    for (size_t q = 0; q < near.size() && static_cast<int>(q) < o.candidates; ++q) {
      const int j = near[q].second;
      cand.emplace_back(i, j);
      src.emplace_back(static_cast<float>(a[i].c[2]), static_cast<float>(a[i].c[1]), static_cast<float>(a[i].c[0]));
      dst.emplace_back(static_cast<float>(b[j].c[2]), static_cast<float>(b[j].c[1]), static_cast<float>(b[j].c[0]));
    }
  }
  if (static_cast<int>(cand.size()) < std::max(4, o.min_matches)) return fallback;

  // 2. RANSAC (OpenCV works in (x, y, z): the fit is re-read in (z, y, x) order).
  cv::Mat aff, inl;
  cv::estimateAffine3D(src, dst, aff, inl, thr, 0.999);
  if (aff.empty()) return fallback;
  StageMap m;
  m.method = "ransac";
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.M(2 - r, 2 - c) = aff.at<double>(r, c);
    m.t(2 - r) = aff.at<double>(r, 3);
  }
  std::vector<std::pair<int, int>> support;
  for (size_t q = 0; q < cand.size(); ++q)
    if (inl.at<uchar>(static_cast<int>(q))) support.push_back(cand[q]);
  if (static_cast<int>(support.size()) < o.min_matches || !fit_affine(a, b, support, m)) return fallback;

  // 3. Polish on mutual nearest pairs under the map.
  for (int round = 0; round < 2; ++round) {
    const auto pairs = mutual_pairs(a, b, m, thr, o.volume_ratio);
    StageMap next = m;
    if (static_cast<int>(pairs.size()) < o.min_matches || !fit_affine(a, b, pairs, next)) break;
    m = next;
  }
  return m;
}

}  // namespace tg::track

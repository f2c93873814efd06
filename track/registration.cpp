#include "track/registration.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
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

  // 1. Candidate pairs: grain-sized A particles, B particles beside them in (y, x).
  std::vector<cv::Point3f> src, dst;
  std::vector<std::pair<int, int>> cand;
  std::vector<std::pair<double, int>> near;
  for (int i = 0; i < static_cast<int>(a.size()); ++i) {
    if (a[i].volume < 0.3 * v_med) continue;
    near.clear();
    for (int j = 0; j < static_cast<int>(b.size()); ++j) {
      if (!similar_volume(a[i].volume, b[j].volume, o.volume_ratio)) continue;
      if (std::abs(b[j].c[0] - a[i].c[0]) > axial) continue;
      const double dy = b[j].c[1] - a[i].c[1], dx = b[j].c[2] - a[i].c[2];
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

#include "segmentation/accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/errors.hpp"

namespace tg {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + long(m), v.end());
  double x = v[m];
  if (v.size() % 2 == 0) x = 0.5 * (x + *std::max_element(v.begin(), v.begin() + long(m)));
  return x;
}

}  // namespace

Accuracy evaluate_labels(const Volume<uint32_t>& truth, const Volume<uint32_t>& pred, const AccuracyOptions& opt) {
  if (truth.shape() != pred.shape())
    throw UsageError("accuracy: truth " + truth.shape().str() + " and labels " + pred.shape().str() + " differ");
  uint32_t mt = 0, mp = 0;
  for (auto l : truth.span()) mt = std::max(mt, l);
  for (auto l : pred.span()) mp = std::max(mp, l);
  std::vector<int64_t> st(size_t(mt) + 1, 0), sp(size_t(mp) + 1, 0);
  std::unordered_map<uint64_t, int64_t> ov;
  const int64_t n = truth.size();
  for (int64_t i = 0; i < n; ++i) {
    const uint32_t t = truth[i], p = pred[i];
    ++st[t], ++sp[p];
    if (t && p) ++ov[(uint64_t(t) << 32) | p];
  }
  Accuracy a;
  a.best_iou.assign(size_t(mt) + 1, 0.0);
  a.match_of.assign(size_t(mt) + 1, 0);
  std::vector<int> pieces_t(size_t(mt) + 1, 0), pieces_p(size_t(mp) + 1, 0);
  for (const auto& [key, c] : ov) {
    const uint32_t t = uint32_t(key >> 32), p = uint32_t(key & 0xffffffffu);
    if (st[t] < opt.min_voxels || sp[p] < opt.min_voxels) continue;
    const double iou = double(c) / double(st[t] + sp[p] - c);
    if (iou > a.best_iou[t]) {
      a.best_iou[t] = iou;
      if (iou >= 0.5) a.match_of[t] = p;
    }
    if (double(c) >= 0.1 * double(st[t])) ++pieces_t[t];
    if (double(c) >= 0.1 * double(st[t])) ++pieces_p[p];
  }
  std::vector<double> err;
  for (uint32_t t = 1; t <= mt; ++t) {
    if (st[t] == 0 || st[t] < opt.min_voxels) continue;
    ++a.n_true;
    if (pieces_t[t] >= 2) ++a.over_segmented;
    if (a.match_of[t]) {
      ++a.matched;
      err.push_back(double(sp[a.match_of[t]] - st[t]) / double(st[t]));
    }
  }
  for (uint32_t p = 1; p <= mp; ++p) {
    if (sp[p] == 0 || sp[p] < opt.min_voxels) continue;
    ++a.n_pred;
    if (pieces_p[p] >= 2) ++a.under_segmenting;
  }
  a.f1 = (a.n_true + a.n_pred) ? 2.0 * double(a.matched) / double(a.n_true + a.n_pred) : 1.0;
  a.median_volume_error = median(err);
  for (auto& e : err) e = std::abs(e);
  a.median_abs_volume_error = median(err);
  return a;
}

}  // namespace tg

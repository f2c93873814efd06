#include "track/rigid_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace tg::track {

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

Eigen::Matrix3d rotation_matrix(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

namespace {

// A box of a volume as floats, smoothed: index (k, j, i) of the box is voxel lo + (k, j, i).
struct Box {
  std::array<int64_t, 3> lo{0, 0, 0}, n{0, 0, 0};
  std::vector<float> v;
  float at(int64_t k, int64_t j, int64_t i) const { return v[static_cast<size_t>((k * n[1] + j) * n[2] + i)]; }
};

// Gaussian of sigma `sigma` voxels along each axis in turn, edges clamped.
void smooth(Box& b, double sigma) {
  if (!(sigma > 0)) return;
  const int r = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> w(static_cast<size_t>(2 * r + 1));
  double sum = 0;
  for (int d = -r; d <= r; ++d) sum += w[static_cast<size_t>(d + r)] = std::exp(-0.5 * d * d / (sigma * sigma));
  for (auto& x : w) x /= sum;
  const int64_t stride[3] = {b.n[1] * b.n[2], b.n[2], 1};
  std::vector<float> line, out(b.v.size());
  for (int ax = 0; ax < 3; ++ax) {
    const int64_t len = b.n[ax];
    line.resize(static_cast<size_t>(len));
    const int a1 = (ax + 1) % 3, a2 = (ax + 2) % 3;
    for (int64_t u = 0; u < b.n[a1]; ++u)
      for (int64_t q = 0; q < b.n[a2]; ++q) {
        const int64_t base = u * stride[a1] + q * stride[a2];
        for (int64_t m = 0; m < len; ++m) line[static_cast<size_t>(m)] = b.v[static_cast<size_t>(base + m * stride[ax])];
        for (int64_t m = 0; m < len; ++m) {
          double acc = 0;
          for (int d = -r; d <= r; ++d)
            acc += w[static_cast<size_t>(d + r)] * line[static_cast<size_t>(std::clamp<int64_t>(m + d, 0, len - 1))];
          out[static_cast<size_t>(base + m * stride[ax])] = static_cast<float>(acc);
        }
      }
    b.v.swap(out);
  }
}

// The box [lo, hi) of v as floats, voxels of labels other than `keep` (and 0) set to `fill`,
// smoothed.
template <class T>
Box box_of(const Volume<T>& v, std::array<int64_t, 3> lo, std::array<int64_t, 3> hi, double sigma,
           const Volume<uint32_t>* labels, uint32_t keep, float fill) {
  const Shape s = v.shape();
  const int64_t dims[3] = {s.nz, s.ny, s.nx};
  Box b;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::clamp<int64_t>(lo[a], 0, dims[a]);
    hi[a] = std::clamp<int64_t>(hi[a], lo[a], dims[a]);
    b.lo[a] = lo[a];
    b.n[a] = hi[a] - lo[a];
  }
  b.v.resize(static_cast<size_t>(b.n[0] * b.n[1] * b.n[2]));
  size_t o = 0;
  for (int64_t k = lo[0]; k < hi[0]; ++k)
    for (int64_t j = lo[1]; j < hi[1]; ++j)
      for (int64_t i = lo[2]; i < hi[2]; ++i) {
        const int64_t n = (k * s.ny + j) * s.nx + i;
        const uint32_t l = labels ? labels->data()[n] : 0;
        b.v[o++] = l && l != keep ? fill : static_cast<float>(v.data()[n]);
      }
  smooth(b, sigma);
  return b;
}

// Catmull-Rom cubic convolution weights (Keys 1981, a = -1/2) of the four samples about f in [0, 1).
inline void cubic_weights(double f, double w[4]) {
  const double f2 = f * f, f3 = f2 * f;
  w[0] = -0.5 * f3 + f2 - 0.5 * f;
  w[1] = 1.5 * f3 - 2.5 * f2 + 1;
  w[2] = -1.5 * f3 + 2 * f2 + 0.5 * f;
  w[3] = 0.5 * f3 - 0.5 * f2;
}

// Cubic-convolution value of a box at y (volume coordinates, voxel centres at k + 0.5): false
// where the 4 x 4 x 4 neighbourhood leaves the box. Trilinear interpolation biased the turn by
// ~0.2 degree on the test's grain (its error at the surface follows the grid, not the grain).
bool sample(const Box& b, const Eigen::Vector3d& y, double& value) {
  const double z = y[0] - 0.5 - static_cast<double>(b.lo[0]), r = y[1] - 0.5 - static_cast<double>(b.lo[1]),
               c = y[2] - 0.5 - static_cast<double>(b.lo[2]);
  if (!(z >= 1 && r >= 1 && c >= 1)) return false;
  const auto k = static_cast<int64_t>(z), j = static_cast<int64_t>(r), i = static_cast<int64_t>(c);
  if (k + 2 >= b.n[0] || j + 2 >= b.n[1] || i + 2 >= b.n[2]) return false;
  double wz[4], wy[4], wx[4];
  cubic_weights(z - static_cast<double>(k), wz);
  cubic_weights(r - static_cast<double>(j), wy);
  cubic_weights(c - static_cast<double>(i), wx);
  const int64_t dj = b.n[2], dk = b.n[1] * b.n[2];
  const float* p0 = b.v.data() + ((k - 1) * b.n[1] + (j - 1)) * b.n[2] + (i - 1);
  double v = 0;
  for (int a = 0; a < 4; ++a) {
    double va = 0;
    for (int q = 0; q < 4; ++q) {
      const float* p = p0 + a * dk + q * dj;
      va += wy[q] * (wx[0] * p[0] + wx[1] * p[1] + wx[2] * p[2] + wx[3] * p[3]);
    }
    v += wz[a] * va;
  }
  value = v;
  return true;
}

// Offsets within `reach` voxels (the centre left out): where a contact's grey reaches.
std::vector<std::array<int64_t, 3>> ball_offsets(double reach) {
  std::vector<std::array<int64_t, 3>> v;
  const auto n = static_cast<int64_t>(std::floor(reach));
  for (int64_t a = -n; a <= n; ++a)
    for (int64_t b = -n; b <= n; ++b)
      for (int64_t c = -n; c <= n; ++c)
        if (static_cast<double>(a * a + b * b + c * c) <= reach * reach && (a || b || c)) v.push_back({a, b, c});
  return v;
}

template <class TA, class TB>
RigidFit fit(const Volume<TA>& A, const Volume<TB>& B, const Volume<uint32_t>& L, uint32_t label,
             const Volume<uint32_t>* LA, uint32_t label_a, const std::array<int64_t, 3>& lo,
             const std::array<int64_t, 3>& hi, const Eigen::Vector3d& t0, const RigidFitOptions& o) {
  RigidFit f;
  const Shape s = L.shape();
  auto at = [&](int64_t k, int64_t j, int64_t i) { return (k * s.ny + j) * s.nx + i; };
  if ((hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) > o.max_box_voxels) return f;
  // B's box: the region (the label and its rim) and the smoothing's reach; A's: that box moved by
  // t0, grown by what the fit may move a voxel (its correction, a turn of up to ~0.1 rad).
  const int64_t pad = 2 + static_cast<int64_t>(std::ceil(3 * o.smoothing_vox));
  double half = 0;
  for (int a = 0; a < 3; ++a) half = std::max(half, 0.5 * static_cast<double>(hi[a] - lo[a]));
  const int64_t grow = pad + static_cast<int64_t>(std::ceil(o.max_correction_vox + 0.1 * half));
  std::array<int64_t, 3> blo, bhi, alo, ahi;
  for (int a = 0; a < 3; ++a) {
    blo[a] = lo[a] - pad, bhi[a] = hi[a] + pad;
    const auto sh = static_cast<int64_t>(std::floor(t0[a]));
    alo[a] = lo[a] + sh - grow, ahi[a] = hi[a] + sh + 1 + grow;
  }
  // Other particles are blanked in both boxes (they move otherwise, and the smoothing and the PSF
  // would carry their grey into the particle's rim) with the grey of the void about it: the
  // median over the region's rim in B. Without it the fit turned large grains by less than half
  // their turn (bench/track RESULTS, "Rotation from the grey levels").
  std::vector<float> rim;
  auto lab = [&](int64_t k, int64_t j, int64_t i) {
    return k >= 0 && j >= 0 && i >= 0 && k < s.nz && j < s.ny && i < s.nx && L.data()[at(k, j, i)] == label;
  };
  auto on_rim = [&](int64_t k, int64_t j, int64_t i) {
    return L.data()[at(k, j, i)] == 0 && (lab(k - 1, j, i) || lab(k + 1, j, i) || lab(k, j - 1, i) ||
                                          lab(k, j + 1, i) || lab(k, j, i - 1) || lab(k, j, i + 1));
  };
  for (int64_t k = std::max<int64_t>(lo[0] - 1, 0); k < std::min(hi[0] + 1, s.nz); ++k)
    for (int64_t j = std::max<int64_t>(lo[1] - 1, 0); j < std::min(hi[1] + 1, s.ny); ++j)
      for (int64_t i = std::max<int64_t>(lo[2] - 1, 0); i < std::min(hi[2] + 1, s.nx); ++i)
        if (on_rim(k, j, i)) rim.push_back(static_cast<float>(B.data()[at(k, j, i)]));
  float fill = 0;
  if (!rim.empty()) {
    std::nth_element(rim.begin(), rim.begin() + static_cast<std::ptrdiff_t>(rim.size() / 2), rim.end());
    fill = rim[rim.size() / 2];
  }
  const Box bb = box_of(B, blo, bhi, o.smoothing_vox, &L, label, fill),
            ab = box_of(A, alo, ahi, o.smoothing_vox, LA, label_a, fill);
  // Large regions are sampled on every second voxel along each axis: the smoothed grey is
  // correlated over ~(2 sqrt(pi) sigma)^3 = 45 voxels, so 1 in 8 keeps most of what it holds,
  // for an eighth of the work.
  int64_t span = 1;
  for (int a = 0; a < 3; ++a) span *= hi[a] - lo[a];
  const int stride = span > o.dense_box_voxels ? 2 : 1;
  // A neighbour's grey reaches ~2 voxels past its label (partial volume and the PSF), and the
  // smoothing carries it further; each voxel left out is one less to turn on. Measured (bench/
  // track RESULTS, "Rotation: how far a contact's grey reaches"): within 2 voxels, the grains of a
  // dense packing read 0.90-0.94 of their turn without noise; within 2 + sigma, 0.98-1.00 but at
  // CNR 13 grains of radius 10 lose more to noise than they gain; 2 + sigma / 2 (0.95-0.98) is
  // better than 2 on the segmented labels of every series measured.
  const std::vector<std::array<int64_t, 3>> near = ball_offsets(2.0 + 0.5 * o.smoothing_vox);
  // The region: the label's voxels and their 6-neighbours in the void, with B's smoothed grey and
  // its gradient (central differences) there.
  std::vector<Eigen::Vector3d> x, gb;
  std::vector<double> g;
  for (int64_t k = std::max<int64_t>(lo[0] - 1, 0); k < std::min(hi[0] + 1, s.nz); ++k)
    for (int64_t j = std::max<int64_t>(lo[1] - 1, 0); j < std::min(hi[1] + 1, s.ny); ++j)
      for (int64_t i = std::max<int64_t>(lo[2] - 1, 0); i < std::min(hi[2] + 1, s.nx); ++i) {
        if (stride > 1 && ((k | j | i) & 1)) continue;
        if (L.data()[at(k, j, i)] != label && !on_rim(k, j, i)) continue;
        // Not where another particle lies within `near`: the PSF and the smoothing carry its
        // grey there, and it does not turn with this one (a contact holds the region still).
        bool near_other = false;
        for (const auto& d : near) {
          const int64_t a = k + d[0], b = j + d[1], c = i + d[2];
          if (a < 0 || b < 0 || c < 0 || a >= s.nz || b >= s.ny || c >= s.nx) continue;
          const uint32_t l = L.data()[at(a, b, c)];
          if (l != 0 && l != label) {
            near_other = true;
            break;
          }
        }
        if (near_other) continue;
        const int64_t bk = k - bb.lo[0], bj = j - bb.lo[1], bi = i - bb.lo[2];
        if (bk < 1 || bj < 1 || bi < 1 || bk + 1 >= bb.n[0] || bj + 1 >= bb.n[1] || bi + 1 >= bb.n[2]) continue;
        x.emplace_back(static_cast<double>(k) + 0.5, static_cast<double>(j) + 0.5, static_cast<double>(i) + 0.5);
        g.push_back(bb.at(bk, bj, bi));
        gb.emplace_back(0.5 * (bb.at(bk + 1, bj, bi) - bb.at(bk - 1, bj, bi)),
                        0.5 * (bb.at(bk, bj + 1, bi) - bb.at(bk, bj - 1, bi)),
                        0.5 * (bb.at(bk, bj, bi + 1) - bb.at(bk, bj, bi - 1)));
      }
  f.voxels = static_cast<int64_t>(x.size());
  if (f.voxels < o.min_voxels) return f;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double reach = 0;  // the region's largest distance from c: a rotation's largest voxel move
  for (const auto& p : x) c += p;
  c /= static_cast<double>(x.size());
  for (const auto& p : x) reach = std::max(reach, (p - c).norm());
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = t0;
  Eigen::Matrix<double, 6, 6> H;
  double ssr = 0;
  int64_t used = 0;
  bool converged = false;
  for (int it = 0; it < o.max_iterations && !converged; ++it) {
    H.setZero();
    Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
    ssr = 0;
    used = 0;
    for (size_t n = 0; n < x.size(); ++n) {
      const Eigen::Vector3d p = x[n] - c;
      double v;
      if (!sample(ab, R * p + c + t, v)) continue;
      const double r = v - g[n];
      // A's gradient at the solution is B's turned by R (B(x) = A(R p + c + t)): B's grid gradient
      // is smooth where the trilinear one of A jumps from cell to cell (which kept the iteration
      // cycling a few hundredths of a voxel about the solution).
      Eigen::Matrix<double, 6, 1> J;
      J << R * gb[n], R * p.cross(gb[n]);
      H.selfadjointView<Eigen::Lower>().rankUpdate(J);
      rhs += J * r;
      ssr += r * r;
      ++used;
    }
    if (used < o.min_voxels) return f;
    H = H.selfadjointView<Eigen::Lower>();
    const Eigen::Matrix<double, 6, 1> d = -H.ldlt().solve(rhs);
    if (!d.allFinite()) return f;
    t += d.head<3>();
    R = rotation_matrix(d.tail<3>()) * R;
    f.iterations = it + 1;
    converged = d.head<3>().norm() + d.tail<3>().norm() * reach <= o.tolerance_vox;
    if ((t - t0).norm() > o.max_correction_vox) return f;
  }
  if (!converged) return f;
  f.ok = true;
  f.t = t;
  f.rms = std::sqrt(ssr / static_cast<double>(used));
  // The particle turns by R^T from A to B.
  f.rotation_deg = -rotation_vector(R) * (180.0 / std::numbers::pi);
  // The residuals of smoothed grey are correlated over the kernel's volume (2 sqrt(pi) sigma)^3
  // (white noise under a Gaussian): that many voxels count as one independent sample.
  const double corr = std::max(1.0, (o.smoothing_vox > 0 ? std::pow(2 * std::sqrt(std::numbers::pi) * o.smoothing_vox, 3) : 1.0) /
                                        std::pow(static_cast<double>(stride), 3));
  const double sigma2 = corr * ssr / static_cast<double>(std::max<int64_t>(1, used - 6));
  const Eigen::Matrix<double, 6, 6> cov = sigma2 * H.inverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov.bottomRightCorner<3, 3>());
  f.rotation_se_deg = std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff())) * (180.0 / std::numbers::pi);
  return f;
}

}  // namespace

RigidFit fit_rigid(const AnyVolume& a, const AnyVolume& b, const Volume<uint32_t>& labels_b, uint32_t label,
                   const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& hi, const Eigen::Vector3d& t0,
                   const RigidFitOptions& o, const Volume<uint32_t>* labels_a, uint32_t label_a) {
  return std::visit(
      [&](const auto& va, const auto& vb) { return fit(va, vb, labels_b, label, labels_a, label_a, lo, hi, t0, o); }, a,
      b);
}

}  // namespace tg::track

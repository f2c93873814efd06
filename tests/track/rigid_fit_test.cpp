// track/rigid_fit: a particle's rotation from its grey levels, against
// rotations and shifts applied analytically: a textured grain (a smooth-edged
// ball holding darker pores and brighter inclusions) rendered at two poses;
// a featureless ball, whose rotation the grey cannot say; the tracker's
// lineage with --scans.
#include "track/rigid_fit.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "track/track.hpp"

using namespace tg;
using namespace tg::track;

namespace {

const Geometry kFitGeom = Geometry::isotropic_m(10e-6);

struct Blob {
  Eigen::Vector3d c;  // in the grain's frame
  double r, level;
};

// Grey of a grain of radius `radius` at centre `c`, turned by R (active), at point x: solid 30000
// over void 10000 with a smooth edge (a blurred surface), blobs adding `level` inside.
double grey(const Eigen::Vector3d& x, const Eigen::Vector3d& c, const Eigen::Matrix3d& R, double radius,
            const std::vector<Blob>& blobs) {
  const Eigen::Vector3d p = R.transpose() * (x - c);
  const double edge = 1.0 / (1.0 + std::exp((p.norm() - radius) / 0.8));
  double v = 10000 + 20000 * edge;
  for (const Blob& b : blobs) v += b.level * edge * std::exp(-(p - b.c).squaredNorm() / (2 * b.r * b.r));
  return v;
}

struct Scene {
  Volume<float> a, b;
  Volume<uint32_t> la, lb;
};

// Noise of sigma `noise` grey levels (seeded: the same every run) on both stages.
Scene render(const Eigen::Matrix3d& R, const Eigen::Vector3d& shift, const std::vector<Blob>& blobs,
             double noise = 0) {
  std::mt19937 rng(20261205);
  std::normal_distribution<double> n01(0, 1);
  const Shape sh{40, 40, 40};
  Scene s{Volume<float>(sh, kFitGeom), Volume<float>(sh, kFitGeom), Volume<uint32_t>::filled(sh, 0, kFitGeom),
          Volume<uint32_t>::filled(sh, 0, kFitGeom)};
  const Eigen::Vector3d c0(19.6, 20.3, 20.1), c1 = c0 + shift;
  const double radius = 11;
  for (int64_t k = 0; k < sh.nz; ++k)
    for (int64_t j = 0; j < sh.ny; ++j)
      for (int64_t i = 0; i < sh.nx; ++i) {
        const Eigen::Vector3d x(k + 0.5, j + 0.5, i + 0.5);
        const int64_t n = sh.index(k, j, i);
        s.a.data()[n] = static_cast<float>(grey(x, c0, Eigen::Matrix3d::Identity(), radius, blobs) + noise * n01(rng));
        s.b.data()[n] = static_cast<float>(grey(x, c1, R, radius, blobs) + noise * n01(rng));
        s.la.data()[n] = (x - c0).norm() <= radius ? 1u : 0u;
        s.lb.data()[n] = (x - c1).norm() <= radius ? 2u : 0u;
      }
  return s;
}

std::vector<Blob> texture() {
  return {{{4, 2, -3}, 2.2, -9000}, {{-5, 3, 2}, 1.8, -8000}, {{1, -6, 4}, 2.5, 6000},
          {{-2, -2, -6}, 2.0, -7000}, {{6, -3, 1}, 1.6, 5000}};
}

std::array<int64_t, 3> lo_of(const Volume<uint32_t>& l, uint32_t label, bool hi) {
  std::array<int64_t, 3> out = hi ? std::array<int64_t, 3>{0, 0, 0} : std::array<int64_t, 3>{1 << 30, 1 << 30, 1 << 30};
  const Shape s = l.shape();
  for (int64_t k = 0; k < s.nz; ++k)
    for (int64_t j = 0; j < s.ny; ++j)
      for (int64_t i = 0; i < s.nx; ++i) {
        if (l.data()[s.index(k, j, i)] != label) continue;
        const int64_t v[3] = {k, j, i};
        for (int a = 0; a < 3; ++a) out[a] = hi ? std::max(out[a], v[a] + 1) : std::min(out[a], v[a]);
      }
  return out;
}

constexpr double kFitDeg = std::numbers::pi / 180;

}  // namespace

// A turn of 2.5 degrees about an oblique axis and a shift of (1.3, -0.7, 2.1) voxels, started half a
// voxel off: the rotation vector comes back within 0.1 degree, the shift within 0.1 voxel.
TEST(RigidFit, RecoversATurnAndAShiftFromTheGreyLevels) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized(), shift(1.3, -0.7, 2.1);
  const Eigen::Vector3d w = 2.5 * kFitDeg * axis;
  const Scene s = render(rotation_matrix(w), shift, texture());
  AnyVolume a = Volume<float>(s.a.shape(), kFitGeom), b = Volume<float>(s.b.shape(), kFitGeom);
  std::copy(s.a.data(), s.a.data() + s.a.size(), std::get<Volume<float>>(a).data());
  std::copy(s.b.data(), s.b.data() + s.b.size(), std::get<Volume<float>>(b).data());
  const RigidFit g = fit_rigid(a, b, s.lb, 2, lo_of(s.lb, 2, false), lo_of(s.lb, 2, true),
                               -shift + Eigen::Vector3d(0.5, -0.4, 0.3));
  ASSERT_TRUE(g.ok);
  for (int ax = 0; ax < 3; ++ax) EXPECT_NEAR(g.rotation_deg[ax], w[ax] / kFitDeg, 0.1) << ax;  // cubic: 0.02-0.05 off (trilinear 0.06-0.23)
  EXPECT_LT(g.rotation_se_deg, 0.05);
  // x_A = R (x_B - c) + c + t: the region's centroid c maps back by -shift (the turn is about the
  // grain's centre, which c is close to).
  EXPECT_LT((g.t + shift).norm(), 0.1);
  EXPECT_LT(g.rms, 100);  // of a 20000 contrast
  // A particle whose box holds more than max_box_voxels is not fitted (a label spanning the scan).
  RigidFitOptions small;
  small.max_box_voxels = 1000;
  EXPECT_FALSE(fit_rigid(a, b, s.lb, 2, lo_of(s.lb, 2, false), lo_of(s.lb, 2, true), -shift, small).ok);
}

// With the scanner's noise (CNR 13: sigma 1500 on a contrast of 20000): the textured grain's turn
// within three standard errors (0.8 degree with five blobs of texture); a ball with no texture, whose turn the grey
// cannot say, fails or says so by its error.
TEST(RigidFit, TheStandardErrorSaysWhatTheGreyHolds) {
  const Eigen::Vector3d w = Eigen::Vector3d(1.2, -0.8, 2.0) * kFitDeg, shift(0.8, 0.4, -1.1);
  {
    const Scene s = render(rotation_matrix(w), shift, texture(), 1500);
    AnyVolume a = Volume<float>(s.a.shape(), kFitGeom), b = Volume<float>(s.b.shape(), kFitGeom);
    std::copy(s.a.data(), s.a.data() + s.a.size(), std::get<Volume<float>>(a).data());
    std::copy(s.b.data(), s.b.data() + s.b.size(), std::get<Volume<float>>(b).data());
    const RigidFit g = fit_rigid(a, b, s.lb, 2, lo_of(s.lb, 2, false), lo_of(s.lb, 2, true), -shift);
    ASSERT_TRUE(g.ok);
    EXPECT_LT(g.rotation_se_deg, 1.5);
    EXPECT_LT((g.rotation_deg - w / kFitDeg).norm(), std::max(0.1, 3 * g.rotation_se_deg)) << g.rotation_deg.transpose();
  }
  const Scene s = render(rotation_matrix(Eigen::Vector3d(0, 0, 3 * kFitDeg)), shift, {}, 1500);
  AnyVolume a = Volume<float>(s.a.shape(), kFitGeom), b = Volume<float>(s.b.shape(), kFitGeom);
  std::copy(s.a.data(), s.a.data() + s.a.size(), std::get<Volume<float>>(a).data());
  std::copy(s.b.data(), s.b.data() + s.b.size(), std::get<Volume<float>>(b).data());
  const RigidFit g = fit_rigid(a, b, s.lb, 2, lo_of(s.lb, 2, false), lo_of(s.lb, 2, true), -shift);
  EXPECT_TRUE(!g.ok || g.rotation_se_deg > 5) << g.rotation_se_deg << " " << g.rotation_deg.transpose();
}

// The tracker with the scans: the particle's lineage row carries the turn; without them nan.
// The first stage's labels and scan spilled to disk between the stages (compare at full size):
// the same turn.
TEST(RigidFit, TrackerWritesTheRotationWithScans) {
  const Eigen::Vector3d w = Eigen::Vector3d(-1.5, 2.0, 1.0) * kFitDeg, shift(0.6, 1.2, -0.9);
  Scene s = render(rotation_matrix(w), shift, texture());
  const std::filesystem::path spill =
      std::filesystem::temp_directory_path() / ("tg_rigid_spill_" + std::to_string(::getpid()) + ".h5");
  auto run = [&](bool scans, bool spilled = false) {
    Tracker tr;
    Volume<uint32_t> la(s.la.shape(), kFitGeom), lb(s.lb.shape(), kFitGeom);
    std::copy(s.la.data(), s.la.data() + s.la.size(), la.data());
    std::copy(s.lb.data(), s.lb.data() + s.lb.size(), lb.data());
    AnyVolume ga, gb;
    if (scans) {
      Volume<float> a(s.a.shape(), kFitGeom), b(s.b.shape(), kFitGeom);
      std::copy(s.a.data(), s.a.data() + s.a.size(), a.data());
      std::copy(s.b.data(), s.b.data() + s.b.size(), b.data());
      ga = std::move(a), gb = std::move(b);
    }
    const int64_t voxels = la.size();
    tr.add_stage(std::move(la), "a", std::move(ga));
    if (spilled) {
      EXPECT_EQ(tr.held_bytes(), voxels * 8);  // u32 labels and the float scan
      tr.spill(spill.string());
      EXPECT_EQ(tr.held_bytes(), 0);
    }
    tr.add_stage(std::move(lb), "b", std::move(gb));
    EXPECT_FALSE(std::filesystem::exists(spill));
    return tr.result();
  };
  const TrackResult r = run(true);
  ASSERT_EQ(r.lineage.size(), 2u);
  const LineageRow& b = r.lineage[1];
  EXPECT_EQ(b.parent_label, 1u);
  for (int ax = 0; ax < 3; ++ax) EXPECT_NEAR(b.rotation_deg[ax], w[ax] / kFitDeg, 0.1) << ax;
  EXPECT_TRUE(std::isnan(r.lineage[0].rotation_deg[0]));  // stage 0: nothing to turn from
  const TrackResult sp = run(true, true);
  for (int ax = 0; ax < 3; ++ax) EXPECT_EQ(sp.lineage[1].rotation_deg[ax], b.rotation_deg[ax]) << ax;
  const TrackResult n = run(false);
  EXPECT_TRUE(std::isnan(n.lineage[1].rotation_deg[0]));
  EXPECT_TRUE(std::isnan(n.lineage[1].rotation_se_deg));
  // A scan of another shape than its labels: refused, naming the stage.
  Tracker tr;
  Volume<uint32_t> la(s.la.shape(), kFitGeom);
  EXPECT_THROW(tr.add_stage(std::move(la), "a", AnyVolume(Volume<float>(Shape{40, 40, 39}, kFitGeom))), InputError);
}

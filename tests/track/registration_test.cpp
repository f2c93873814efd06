// track/registration: the RANSAC map between stages against known affine maps.
#include "track/registration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "data_synth/rng.hpp"

using tg::track::estimate_map;
using tg::track::MapOptions;
using tg::track::Point;

namespace {

// A jittered lattice of grain centres (radius ~6 voxels) in a 100-voxel-high specimen.
std::vector<Point> lattice(uint64_t seed) {
  std::vector<Point> p;
  uint64_t n = 0;
  for (int k = 0; k < 7; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 5; ++i, ++n)
        p.push_back({{8.0 + 13 * k + tg::synth::uniform01(seed, n, 0), 8.0 + 13 * j + tg::synth::uniform01(seed, n, 1),
                      8.0 + 13 * i + tg::synth::uniform01(seed, n, 2)},
                     900 + 100 * tg::synth::uniform01(seed, n, 3)});
  return p;
}

}  // namespace

// Uniform compression about the bottom (z = 0) by 6 %, a lateral shift and a
// small shear; 20 % of the particles replaced by others of random volume
// and place (broken grains, new fragments): the fit recovers the map.
TEST(Registration, RecoversCompressionWithOutliers) {
  const auto a = lattice(3);
  std::vector<Point> b;
  Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  M(0, 0) = 0.94;
  M(1, 0) = 0.01;  // a little shear
  const Eigen::Vector3d t(0.0, 1.2, -0.7);
  for (size_t q = 0; q < a.size(); ++q) {
    if (q % 5 == 0) {  // replaced: a fragment somewhere else
      b.push_back({{100 * tg::synth::uniform01(7, q, 0), 60 * tg::synth::uniform01(7, q, 1), 60 * tg::synth::uniform01(7, q, 2)},
                   300 + 200 * tg::synth::uniform01(7, q, 3)});
      continue;
    }
    const Eigen::Vector3d y = M * Eigen::Vector3d(a[q].c[0], a[q].c[1], a[q].c[2]) + t;
    b.push_back({{y[0] + 0.2 * (tg::synth::uniform01(9, q, 0) - 0.5), y[1], y[2]}, a[q].volume});
  }
  const auto m = estimate_map(a, b, 100.0);
  EXPECT_EQ(m.method, "ransac");
  EXPECT_NEAR(m.axial_scale(), 0.94, 2e-3);
  EXPECT_NEAR(m.M(1, 0), 0.01, 2e-3);
  EXPECT_NEAR(m.t(1), 1.2, 0.1);
  EXPECT_NEAR(m.t(2), -0.7, 0.1);
  EXPECT_GE(m.matches, static_cast<int>(0.75 * a.size()));
  EXPECT_LT(m.rms_vox, 0.2);
}

// Too few particles: the fallback is identity plus the stated axial compression about the fixed plane.
TEST(Registration, FallbackWithFewGrains) {
  std::vector<Point> a{{{10, 10, 10}, 500}, {{30, 10, 10}, 500}}, b = a;
  MapOptions o;
  o.fallback_strain = 0.05;
  o.fixed_plane_vox = 4;
  const auto m = estimate_map(a, b, 64, o);
  EXPECT_EQ(m.method, "fallback");
  const auto y = m.apply({24, 10, 10});
  EXPECT_NEAR(y[0], 4 + 0.95 * 20, 1e-12);
  EXPECT_NEAR(y[1], 10, 1e-12);
  EXPECT_EQ(estimate_map({}, b, 64, o).method, "identity");
}

// The specimen remounted between the stages: shifted sideways by more than
// a grain radius, or turned about its axis (any angle), on top of a 5 %
// compression; 20 % of the particles replaced as above. Before the prior of
// step 0 (registration.hpp) every case below fell back (no candidate pair
// within the lateral radius).
TEST(Registration, RecoversARemountedSpecimenShiftedOrTurned) {
  // A random packing (not lattice(): a lattice turned by 90 degrees is itself
  // shifted, and no map can tell them apart): centres at least 11 voxels
  // apart in a 100 x 120 x 120 box, volumes 700-1100.
  std::vector<Point> a;
  for (uint64_t n = 0; n < 20000 && a.size() < 450; ++n) {
    const std::array<double, 3> c{6 + 88 * tg::synth::uniform01(5, n, 0), 6 + 108 * tg::synth::uniform01(5, n, 1),
                                  6 + 108 * tg::synth::uniform01(5, n, 2)};
    bool free = true;
    for (const Point& p : a)
      free = free && std::hypot(p.c[0] - c[0], p.c[1] - c[1], p.c[2] - c[2]) >= 11;
    if (free) a.push_back({c, 700 + 400 * tg::synth::uniform01(5, n, 3)});
  }
  ASSERT_GE(a.size(), 300u);
  const double cy = 60, cx = 60;  // the turn's axis
  for (const double deg : {0.0, 25.0, 90.0, 200.0}) {
    const double th = deg * std::numbers::pi / 180, c = std::cos(th), s = std::sin(th);
    Eigen::Matrix3d M;
    M << 0.95, 0, 0, 0, c, -s, 0, s, c;
    const Eigen::Vector3d t = Eigen::Vector3d(0, cy, cx) - M * Eigen::Vector3d(0, cy, cx) + Eigen::Vector3d(0, 9.0, -14.0);
    std::vector<Point> b;
    for (size_t q = 0; q < a.size(); ++q) {
      if (q % 5 == 0) {
        b.push_back({{100 * tg::synth::uniform01(7, q, 0), 120 * tg::synth::uniform01(7, q, 1),
                      120 * tg::synth::uniform01(7, q, 2)},
                     300 + 200 * tg::synth::uniform01(7, q, 3)});
        continue;
      }
      const Eigen::Vector3d y = M * Eigen::Vector3d(a[q].c[0], a[q].c[1], a[q].c[2]) + t;
      b.push_back({{y[0], y[1], y[2]}, a[q].volume});
    }
    const auto m = estimate_map(a, b, 100.0);
    SCOPED_TRACE(deg);
    EXPECT_EQ(m.method, "ransac");
    EXPECT_NEAR(m.axial_scale(), 0.95, 2e-3);
    EXPECT_NEAR(m.M(1, 1), c, 2e-3);
    EXPECT_NEAR(m.M(2, 1), s, 2e-3);
    EXPECT_NEAR(m.t(1), t(1), 0.2);
    EXPECT_NEAR(m.t(2), t(2), 0.2);
    EXPECT_GE(m.matches, static_cast<int>(0.75 * a.size()));
  }
}

// track/registration: the RANSAC map between stages against known affine maps.
#include "track/registration.hpp"

#include <gtest/gtest.h>

#include <cmath>

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

#include "data_synth/render.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

using namespace tg::synth;

namespace {
std::vector<Particle> some_particles() {
  std::vector<Particle> ps;
  ps.push_back(make_grain(1, {10.3, 12.1, 11.7}, 6.2));
  ps.push_back(make_grain(2, {10.3, 12.1, 24.0}, 6.0));  // touching-ish neighbour
  ps.push_back(make_cap(3, Kind::half, 7, {{24.6, 20.2, 18.5}, 7.1}, {0.2, 0.9, -0.3}, 0.75));
  ps.push_back(make_cap(4, Kind::half, 7, {{24.6, 20.2, 18.5}, 7.1}, {-0.2, -0.9, 0.3}, 0.75));
  ps.push_back(make_cluster(5, 9, {{{8, 28, 8}, 3}, {{8, 28, 12}, 3}}));
  ps.push_back(make_grain(6, {-2.0, 30.0, 30.0}, 5.0));  // crosses the volume border
  ps[0].pores.push_back({{11, 12, 12}, 2});
  return ps;
}
}  // namespace

TEST(Render, ByteIdenticalForOneAndTwoThreads) {
  const auto ps = some_particles();
  const tg::Shape shape{33, 35, 37};
  omp_set_num_threads(1);
  const Rendered a = render(ps, shape, {}, {.slab = 3});
  omp_set_num_threads(2);
  const Rendered b = render(ps, shape, {}, {.slab = 3});
  ASSERT_EQ(a.solid.size(), b.solid.size());
  EXPECT_EQ(std::memcmp(a.solid.data(), b.solid.data(), a.solid.bytes()), 0);
  EXPECT_EQ(std::memcmp(a.labels.data(), b.labels.data(), a.labels.bytes()), 0);
}

TEST(Render, SolidSumEqualsTruthVolumes) {
  auto ps = some_particles();
  ps.pop_back();  // keep only particles fully inside
  const tg::Shape shape{40, 40, 40};
  const Rendered r = render(ps, shape);
  double sum = 0;
  for (float v : r.solid.span()) sum += v;
  double truth = 0;
  for (const Particle& p : ps) truth += particle_truth(p).volume;
  // Separate particles (no overlaps): only the f32 storage and the cut-voxel rule err.
  EXPECT_NEAR(sum, truth, 1e-5 * truth);
}

TEST(Render, LabelsAreConsistentWithCoverage) {
  const auto ps = some_particles();
  const tg::Shape shape{33, 35, 37};
  const Rendered r = render(ps, shape);
  std::vector<int64_t> count(8, 0);
  for (int64_t q = 0; q < r.solid.size(); ++q) {
    const uint32_t l = r.labels[q];
    if (r.solid[q] < 0.5f) EXPECT_EQ(l, 0u);
    else EXPECT_NE(l, 0u);
    ++count[l];
  }
  // Label counts of a sphere fully inside approximate its volume within its surface shell.
  const double v1 = particle_truth(ps[1]).volume, area = 4 * std::numbers::pi * 36;
  EXPECT_NEAR(static_cast<double>(count[2]), v1, 0.5 * area * 0.5);
  // Every voxel whose centre is deep inside grain 2 is labelled 2.
  EXPECT_EQ(r.labels(10, 12, 24), 2u);
  EXPECT_EQ(r.solid(0, 0, 0), 0.0f);
  // The two half caps 3 and 4 of one sphere (centre c, radius 7.1) are cut by
  // planes n.(p - c) = +-0.75: a voxel whose centre lies well inside the
  // sphere is labelled 3 beyond +1.75 (its cube, half-diagonal 0.87, lies
  // wholly in cap 3), 4 below -1.75, and 0 inside the 1.5-wide gap (|s| < 0.25:
  // less than half of its cube reaches a cap). Computed here from the
  // geometry, independently of the renderer.
  const double c[3] = {24.6, 20.2, 18.5}, len = std::sqrt(0.2 * 0.2 + 0.9 * 0.9 + 0.3 * 0.3);
  const double n[3] = {0.2 / len, 0.9 / len, -0.3 / len};
  int64_t seen3 = 0, seen4 = 0, seen_gap = 0;
  for (int64_t k = 0; k < shape.nz; ++k)
    for (int64_t j = 0; j < shape.ny; ++j)
      for (int64_t i = 0; i < shape.nx; ++i) {
        const double d[3] = {k + 0.5 - c[0], j + 0.5 - c[1], i + 0.5 - c[2]};
        if (std::hypot(d[0], d[1], d[2]) > 7.1 - 1) continue;
        const double s = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
        if (s > 1.75) {
          EXPECT_EQ(r.labels(k, j, i), 3u) << k << ' ' << j << ' ' << i;
          ++seen3;
        }
        if (s < -1.75) {
          EXPECT_EQ(r.labels(k, j, i), 4u) << k << ' ' << j << ' ' << i;
          ++seen4;
        }
        if (std::abs(s) < 0.25) {
          EXPECT_EQ(r.labels(k, j, i), 0u) << k << ' ' << j << ' ' << i;
          ++seen_gap;
        }
      }
  EXPECT_GT(seen3, 200);
  EXPECT_GT(seen4, 200);
  EXPECT_GT(seen_gap, 20);
}

TEST(Render, RejectsDuplicateIds) {
  std::vector<Particle> ps{make_grain(1, {5, 5, 5}, 2), make_grain(1, {9, 9, 9}, 2)};
  EXPECT_THROW(render(ps, tg::Shape{12, 12, 12}), tg::UsageError);
  ps[1].id = 0;
  EXPECT_THROW(render(ps, tg::Shape{12, 12, 12}), tg::UsageError);
}

TEST(Render, EmptyParticleListGivesEmptyVolume) {
  const Rendered r = render({}, tg::Shape{4, 5, 6});
  for (float v : r.solid.span()) EXPECT_EQ(v, 0.0f);
  for (uint32_t v : r.labels.span()) EXPECT_EQ(v, 0u);
}

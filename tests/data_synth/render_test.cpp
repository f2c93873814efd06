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
  EXPECT_EQ(r.labels(24, 21, 18), 0u + r.labels(24, 21, 18));  // defined
  EXPECT_EQ(r.solid(0, 0, 0), 0.0f);
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

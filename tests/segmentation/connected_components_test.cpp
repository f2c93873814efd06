#include "segmentation/connected_components.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <map>
#include <random>

#include <omp.h>

#include "core/errors.hpp"

namespace tg {
namespace {

// Oracle: breadth-first flood fill started from each unlabelled foreground
// voxel in raster order, neighbours enumerated by explicit loops and a
// squared-distance test (1: faces, 2: +edges, 3: +corners).
std::vector<uint32_t> flood_oracle(const Volume<uint8_t>& m, int conn, bool zero_phase, uint32_t& count) {
  const Shape s = m.shape();
  const int maxd2 = conn == 6 ? 1 : conn == 18 ? 2 : 3;
  std::vector<uint32_t> lab(size_t(m.size()), 0);
  auto fg = [&](int64_t idx) { return zero_phase ? m[idx] == 0 : m[idx] != 0; };
  count = 0;
  for (int64_t start = 0; start < m.size(); ++start) {
    if (!fg(start) || lab[size_t(start)]) continue;
    lab[size_t(start)] = ++count;
    std::deque<int64_t> q{start};
    while (!q.empty()) {
      const auto [k, j, i] = s.coords(q.front());
      q.pop_front();
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int d2 = dz * dz + dy * dy + dx * dx;
            if (d2 == 0 || d2 > maxd2 || !s.contains(k + dz, j + dy, i + dx)) continue;
            const int64_t n = s.index(k + dz, j + dy, i + dx);
            if (fg(n) && !lab[size_t(n)]) {
              lab[size_t(n)] = count;
              q.push_back(n);
            }
          }
    }
  }
  return lab;
}

Volume<uint8_t> random_mask(Shape s, double p, unsigned seed) {
  Volume<uint8_t> m(s);
  std::mt19937 rng(seed);
  std::bernoulli_distribution b(p);
  for (auto& v : m.span()) v = b(rng) ? 1 : 0;
  return m;
}

TEST(ConnectedComponents, MatchesFloodFillOracle) {
  unsigned seed = 3;
  for (int conn : {6, 18, 26})
    for (double p : {0.2, 0.35, 0.6})
      for (Phase ph : {Phase::nonzero, Phase::zero}) {
        const auto m = random_mask(Shape{13, 17, 19}, p, seed++);
        Volume<uint32_t> lab;
        const auto r = connected_components(m, lab, {conn, ph, 1});
        uint32_t count = 0;
        const auto want = flood_oracle(m, conn, ph == Phase::zero, count);
        ASSERT_EQ(r.count, count) << "conn " << conn << " p " << p;
        for (int64_t i = 0; i < m.size(); ++i) ASSERT_EQ(lab[i], want[size_t(i)]) << "voxel " << i;
        int64_t total = 0;
        for (uint32_t l = 1; l <= r.count; ++l) total += r.sizes[l];
        int64_t fg = 0;
        for (auto v : m.span()) fg += ph == Phase::zero ? v == 0 : v != 0;
        EXPECT_EQ(total, fg);
      }
}

TEST(ConnectedComponents, SizeFilterAndConsecutiveLabels) {
  const auto m = random_mask(Shape{20, 20, 20}, 0.25, 11);
  Volume<uint32_t> lab;
  const auto r = connected_components(m, lab, {6, Phase::nonzero, 4});
  uint32_t count = 0;
  const auto want = flood_oracle(m, 6, false, count);
  std::vector<int64_t> osize(count + 1, 0);
  for (auto l : want) ++osize[l];
  int64_t kept = 0, dropped = 0;
  for (uint32_t l = 1; l <= count; ++l) (osize[l] >= 4 ? kept : dropped)++;
  EXPECT_EQ(int64_t(r.count), kept);
  EXPECT_EQ(r.dropped, dropped);
  ASSERT_GT(dropped, 0);
  // Kept voxels keep their component (consecutive, in raster order), dropped ones are 0.
  std::vector<uint32_t> seen(count + 1, 0);
  uint32_t next = 0;
  for (int64_t i = 0; i < m.size(); ++i) {
    const uint32_t o = want[size_t(i)];
    if (o == 0 || osize[o] < 4) {
      EXPECT_EQ(lab[i], 0u);
      continue;
    }
    if (!seen[o]) seen[o] = ++next;
    EXPECT_EQ(lab[i], seen[o]);
    EXPECT_GE(r.sizes[lab[i]], 4);
  }
}

TEST(ConnectedComponents, DiagonalNeighboursDependOnConnectivity) {
  auto m = Volume<uint8_t>::filled(Shape{2, 2, 2}, 0);
  m(0, 0, 0) = 1, m(1, 1, 1) = 1;  // corner-touching pair
  m(0, 1, 1) = 0;
  Volume<uint32_t> lab;
  EXPECT_EQ(connected_components(m, lab, {6}).count, 2u);
  EXPECT_EQ(connected_components(m, lab, {18}).count, 2u);
  EXPECT_EQ(connected_components(m, lab, {26}).count, 1u);
}

TEST(ConnectedComponents, EmptyFullAndInvalid) {
  Volume<uint32_t> lab;
  EXPECT_EQ(connected_components(Volume<uint8_t>::filled(Shape{4, 5, 6}, 0), lab).count, 0u);
  const auto r = connected_components(Volume<uint8_t>::filled(Shape{4, 5, 6}, 1), lab);
  EXPECT_EQ(r.count, 1u);
  EXPECT_EQ(r.sizes[1], 120);
  EXPECT_EQ(connected_components(Volume<uint8_t>(Shape{0, 0, 0}), lab).count, 0u);
  EXPECT_THROW(connected_components(Volume<uint8_t>::filled(Shape{1, 1, 1}, 1), lab, {8}), UsageError);
}

// Slabs of slices are labelled by threads and joined at their seams: any
// thread count (1 to 5 threads: 4 to 20 slabs over 37 slices) must give the
// oracle's labels, components that cross many seams included.
TEST(ConnectedComponents, AnyThreadCountGivesTheOracle) {
  const int before = omp_get_max_threads();
  unsigned seed = 40;
  for (int conn : {6, 18, 26})
    for (double p : {0.3, 0.55}) {
      const auto m = random_mask(Shape{37, 23, 29}, p, seed++);
      uint32_t count = 0;
      const auto want = flood_oracle(m, conn, false, count);
      for (int threads : {1, 2, 3, 5}) {
        omp_set_num_threads(threads);
        Volume<uint32_t> lab;
        const auto r = connected_components(m, lab, {conn, Phase::nonzero, 1});
        ASSERT_EQ(r.count, count) << "conn " << conn << " threads " << threads;
        for (int64_t i = 0; i < m.size(); ++i)
          ASSERT_EQ(lab[i], want[size_t(i)]) << "conn " << conn << " threads " << threads << " voxel " << i;
      }
    }
  omp_set_num_threads(before);
}

TEST(RelabelConsecutive, AnyThreadCountGivesRasterOrder) {
  const int before = omp_get_max_threads();
  std::mt19937 rng(5);
  std::uniform_int_distribution<uint32_t> pick(0, 300);
  Volume<uint32_t> in(Shape{11, 13, 17});
  for (auto& v : in.span()) v = pick(rng) < 40 ? 0u : pick(rng) * 7u;  // sparse, unordered labels
  // Expected: a plain serial scan.
  std::map<uint32_t, int64_t> size;
  for (auto v : in.span()) ++size[v];
  std::map<uint32_t, uint32_t> to{{0u, 0u}};
  uint32_t next = 0;
  for (auto v : in.span())
    if (!to.count(v)) to[v] = size[v] >= 3 ? ++next : 0u;
  for (int threads : {1, 2, 3}) {
    omp_set_num_threads(threads);
    Volume<uint32_t> lab = in.clone();
    const auto r = relabel_consecutive(lab, 3);
    ASSERT_EQ(r.count, next) << threads << " threads";
    for (int64_t i = 0; i < lab.size(); ++i) ASSERT_EQ(lab[i], to[in[i]]) << threads << " threads, voxel " << i;
    for (uint32_t l = 1; l <= r.count; ++l) EXPECT_GE(r.sizes[l], 3);
  }
  omp_set_num_threads(before);
}

// A premap (a merge's roots: each root maps to itself, others to a smaller
// root) is applied in the same pass: the result equals applying it first.
TEST(RelabelConsecutive, PremapEqualsApplyingItFirst) {
  Volume<uint32_t> lab(Shape{1, 2, 9});
  const uint32_t in[] = {0, 7, 7, 3, 9, 9, 5, 0, 2, 4, 4, 8, 1, 0, 6, 6, 6, 9};
  std::copy(in, in + 18, lab.begin());
  std::vector<uint32_t> root(10);
  for (uint32_t l = 0; l < 10; ++l) root[l] = l;
  root[7] = 3, root[9] = 2, root[5] = 2, root[8] = 1;  // 7 -> 3, 9 and 5 -> 2, 8 -> 1
  Volume<uint32_t> first = lab.clone();
  for (auto& v : first.span()) v = root[v];
  const auto want = relabel_consecutive(first, 3);  // drops 8 -> 1 and 4 (2 voxels each)
  const auto got = relabel_consecutive(lab, 3, &root);
  EXPECT_EQ(got.count, want.count);
  EXPECT_EQ(got.dropped, want.dropped);
  EXPECT_EQ(got.sizes, want.sizes);
  for (int64_t i = 0; i < lab.size(); ++i) EXPECT_EQ(lab[i], first[i]) << i;
  EXPECT_GT(want.dropped, 0);
}

TEST(RelabelConsecutive, RenumbersInRasterOrder) {
  Volume<uint32_t> lab(Shape{1, 1, 8});
  const uint32_t in[] = {0, 70, 70, 5, 900, 5, 5, 0};
  std::copy(in, in + 8, lab.begin());
  const auto r = relabel_consecutive(lab, 2);  // 900 has one voxel: dropped
  const uint32_t want[] = {0, 1, 1, 2, 0, 2, 2, 0};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(lab[i], want[i]);
  EXPECT_EQ(r.count, 2u);
  EXPECT_EQ(r.dropped, 1);
  EXPECT_EQ(r.sizes[2], 3);
}

}  // namespace
}  // namespace tg

// compare/dem_lineage: the DEM's exact lineage from the snapshots'
// previous_particle column, on a hand-made chain of three snapshots:
//   snapshot 0  grain A (particle 0, bottom), grain B (particle 1, top)
//   snapshot 1  A split in two halves: particles 0 and 2 (both from 0); B intact
//   snapshot 2  the half 2 split again: particles 2 and 3 (both from 2)
// Hand counts: stage 1 one split (A), stage 2 one split (fragment 2); 1 of 2
// grains broken from stage 1 on, in the bottom fifth; comparing snapshots 0
// and 2 directly, A's three pieces (1/2, 1/4, 1/4) are one fragmentation.
#include "compare/dem_lineage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <tuple>

#include "core/errors.hpp"

namespace tg::compare {
namespace {

constexpr double kVox = 1e-4;  // 0.1 mm voxels: a 1 mm grain is ~4189 voxels

// One sphere per particle: (particle, previous, z, volume share of a 1 mm-radius grain).
SnapshotLineage snapshot(const std::vector<std::tuple<int64_t, int64_t, double, double>>& rows, const std::string& name) {
  SnapshotLineage s;
  s.source = name;
  for (const auto& [id, prev, z, share] : rows) {
    s.spheres.push_back(0, 0, z, 1e-3 * std::cbrt(share), id);
    s.previous_particle.push_back(prev);
  }
  return s;
}

std::vector<SnapshotLineage> chain() {
  return {snapshot({{0, 0, 1e-3, 1}, {1, 1, 9e-3, 1}}, "s0"),
          snapshot({{0, 0, 0.8e-3, 0.5}, {2, 0, 1.6e-3, 0.5}, {1, 1, 8.9e-3, 1}}, "s1"),
          snapshot({{0, 0, 0.8e-3, 0.5}, {2, 2, 1.5e-3, 0.25}, {3, 2, 1.9e-3, 0.25}, {1, 1, 8.8e-3, 1}}, "s2")};
}

std::map<int64_t, uint32_t> labels_plus(uint32_t offset, const std::vector<int64_t>& ids) {
  std::map<int64_t, uint32_t> m;
  for (int64_t id : ids) m[id] = static_cast<uint32_t>(id) + offset;
  return m;
}

TEST(DemLineage, SplitThenFragmentSplitAgain) {
  // Labels differ from the ids (as voxelised truth labels do): id + 10 at every stage.
  const auto r = dem_lineage(chain(), {0, 1, 2},
                             {labels_plus(10, {0, 1}), labels_plus(10, {0, 1, 2}), labels_plus(10, {0, 1, 2, 3})}, kVox);
  ASSERT_EQ(r.summary.size(), 3u);
  EXPECT_EQ(r.summary[1].split, 1);
  EXPECT_EQ(r.summary[1].fragmentation + r.summary[1].chipping + r.summary[1].lost + r.summary[1].new_particles, 0);
  EXPECT_EQ(r.summary[2].split, 1);
  EXPECT_EQ(r.summary[2].fragmentation + r.summary[2].chipping + r.summary[2].lost + r.summary[2].new_particles, 0);
  for (int s = 1; s < 3; ++s) {
    EXPECT_EQ(r.summary[s].grains_broken, 1) << s;
    EXPECT_EQ(r.summary[s].grains_intact, 1) << s;
    EXPECT_DOUBLE_EQ(r.summary[s].pct_intact_broken, 50) << s;
    EXPECT_DOUBLE_EQ(r.summary[s].pct_broken_band[0], 100) << s;  // A: bottom fifth
    EXPECT_DOUBLE_EQ(r.summary[s].pct_broken_band[4], 0) << s;    // B: top fifth
  }
  EXPECT_EQ(r.summary[1].breaks_band[0], 1);
  // Stage 2: particle 3 (label 13) comes from fragment 2 (label 12) of grain A (label 10).
  bool seen = false;
  for (const auto& row : r.lineage)
    if (row.stage == 2 && row.label == 13) {
      seen = true;
      EXPECT_EQ(row.parent_label, 12u);
      EXPECT_EQ(row.grain, 10u);
      EXPECT_EQ(row.event, track::Event::split);
      EXPECT_EQ(row.volume_vox, std::llround(4.0 / 3.0 * std::numbers::pi * 1000 * 0.25));
    }
  EXPECT_TRUE(seen);
}

TEST(DemLineage, ComposesOverSkippedSnapshots) {
  // Stages at snapshots 0 and 2: snapshot 1's map is composed in between.
  const auto r = dem_lineage(chain(), {0, 2}, {labels_plus(1, {0, 1}), labels_plus(1, {0, 1, 2, 3})}, kVox);
  ASSERT_EQ(r.summary.size(), 2u);
  EXPECT_EQ(r.summary[1].fragmentation, 1);  // three pieces, the largest half of the total: < 0.7
  EXPECT_EQ(r.summary[1].split + r.summary[1].chipping, 0);
  EXPECT_DOUBLE_EQ(r.summary[1].pct_intact_broken, 50);
  for (const auto& row : r.lineage) {
    if (row.stage == 1) {
      EXPECT_EQ(row.parent_label, row.label == 2 ? 2u : 1u) << row.label;  // B (label 2) or A (label 1)
    }
  }
}

TEST(DemLineage, SameSnapshotTwiceIsIntact) {
  const auto r = dem_lineage(chain(), {1, 1}, {labels_plus(1, {0, 1, 2}), labels_plus(1, {0, 1, 2})}, kVox);
  EXPECT_EQ(r.summary[1].grains_broken, 0);
  EXPECT_EQ(r.summary[1].grains_intact, 3);
}

TEST(DemLineage, MissingOrInconsistentColumnIsAnInputError) {
  auto c = chain();
  c[1].previous_particle.clear();  // a run written before the column existed
  EXPECT_THROW(dem_lineage(c, {0, 1}, {labels_plus(1, {0, 1}), labels_plus(1, {0, 1, 2})}, kVox), InputError);
  c = chain();
  c[2].previous_particle[1] = 7;  // names a particle snapshot 1 does not have
  EXPECT_THROW(dem_lineage(c, {1, 2}, {labels_plus(1, {0, 1, 2}), labels_plus(1, {0, 1, 2, 3})}, kVox), InputError);
}

TEST(DemLineage, OnGridShiftsByWholeVoxels) {
  auto v = Volume<uint32_t>::filled(Shape{2, 2, 2}, 0, Geometry::isotropic_m(1.0));
  v.geometry().origin_m = {1, 0, 0};  // one voxel higher than the target grid
  v.data()[0] = 5;                    // (0, 0, 0) -> (1, 0, 0)
  v.data()[7] = 6;                    // (1, 1, 1) -> (2, 1, 1): outside a 2-voxel-high grid, cut
  const auto out = on_grid(v, Shape{2, 3, 3}, Geometry::isotropic_m(1.0));
  EXPECT_EQ(out.data()[(1 * 3 + 0) * 3 + 0], 5u);
  int64_t solid = 0;
  for (int64_t q = 0; q < out.size(); ++q) solid += out.data()[q] != 0;
  EXPECT_EQ(solid, 1);
}

}  // namespace
}  // namespace tg::compare

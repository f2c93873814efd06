// segment_chunked (a scan larger than memory, slab by slab) against segment()
// on the whole volume: the in-memory path is the independent answer, and
// the labels must match voxel for voxel, number for number.
#include <gtest/gtest.h>

#include <array>

#include <cmath>
#include <cstdlib>

#include "core/errors.hpp"
#include "segmentation/segment.hpp"
#include "segmentation/segment_chunked.hpp"
#include "scan_scenes.hpp"

namespace tg {
namespace {

// A tall scan of blurred, noisy balls of radius 6 (overlapping: clusters
// that the watershed splits and the merge repairs), so that slabs of 32
// core slices with 48 slices of margin cut it into 6 slabs whose reads
// are truncated by the margins, not by the scan's ends.
Volume<uint16_t> chunk_scan(bool outside_constant) {
  const Shape s{192, 64, 64};
  const auto truth = test::ball_packing(s, 6.0, 0.45, 2301);
  auto g = test::image(truth, 0.7, nullptr, 2302);
  if (outside_constant)  // a reconstruction's field of view: 0 outside a circle of radius 30
    for (int64_t k = 0; k < s.nz; ++k)
      for (int64_t j = 0; j < s.ny; ++j)
        for (int64_t i = 0; i < s.nx; ++i)
          if (std::hypot(double(j) - 31.5, double(i) - 31.5) > 30.0) g(k, j, i) = 0;
  g.set_geometry(Geometry::isotropic_m(30e-6));
  return g;
}

SegmentOptions chunk_options() {
  SegmentOptions o;
  o.grain_radius_vox = 6.0;
  o.min_size_vox = 40;  // drops some slivers, so the numbering skips as segment()'s does
  return o;
}

// The memory limit that gives slabs of `core` core slices (plan_chunks' rule).
int64_t limit_for(const Shape& s, int64_t core, int64_t margin) {
  return kSegmentFixedBytes + int64_t(ChunkedOptions{}.bytes_per_voxel * double(s.slice_voxels()) * double(core + 2 * margin)) + 1;
}

struct ChunkRun {
  ChunkedResult res;
  Volume<uint32_t> labels;
};

ChunkRun run_chunked(const Volume<uint16_t>& scan, const SegmentOptions& o, const ChunkPlan& plan) {
  setenv("TOMOGRAIN_QUIET", "1", 0);  // no progress lines in the test log
  ChunkRun run;
  run.labels = Volume<uint32_t>::filled(scan.shape(), 0xffffffffu);
  const int64_t sl = scan.shape().slice_voxels();
  auto read = [&](int64_t z0, int64_t nz) {
    Volume<uint16_t> v(Shape{nz, scan.shape().ny, scan.shape().nx}, scan.geometry());
    std::copy(scan.data() + z0 * sl, scan.data() + (z0 + nz) * sl, v.data());
    return v;
  };
  auto write = [&](int64_t z0, const Volume<uint32_t>& l, int64_t vz0, int64_t nz) {
    std::copy(l.data() + vz0 * sl, l.data() + (vz0 + nz) * sl, run.labels.data() + z0 * sl);
  };
  run.res = segment_chunked(scan.shape(), scan.geometry(), read, write, o, plan);
  return run;
}

void expect_same_labels(const SegmentResult& whole, const ChunkRun& run) {
  EXPECT_EQ(run.res.result.count, whole.count);
  EXPECT_EQ(run.res.result.dropped, whole.dropped);
  EXPECT_EQ(run.res.result.threshold.value, whole.threshold.value);
  EXPECT_EQ(run.res.result.bright_value, whole.bright_value);
  EXPECT_DOUBLE_EQ(run.res.result.solid_fraction, whole.solid_fraction);
  int64_t differ = 0, first = -1;
  for (int64_t i = 0; i < whole.labels.size(); ++i)
    if (whole.labels[i] != run.labels[i]) {
      if (first < 0) first = i;
      ++differ;
    }
  EXPECT_EQ(differ, 0) << "first at voxel " << first << " (z " << (first / whole.labels.shape().slice_voxels())
                       << "): " << (first >= 0 ? whole.labels[first] : 0) << " in one piece, "
                       << (first >= 0 ? run.labels[first] : 0) << " by slabs";
}

}  // namespace

// Six slabs (32 core + 2 x 48 margin slices), the limit from the rule:
// identical labels, counts, threshold and solid fraction.
TEST(SegmentChunked, SameLabelsAsWholeVolume) {
  const auto scan = chunk_scan(false);
  const SegmentOptions o = chunk_options();
  const SegmentResult whole = segment(scan, o);
  ASSERT_GT(whole.count, 40u);
  ChunkedOptions co;
  co.memory_limit_bytes = limit_for(scan.shape(), 32, 48);
  const ChunkPlan plan = plan_chunks(scan.shape(), o.grain_radius_vox, co);
  ASSERT_FALSE(plan.in_memory);
  EXPECT_EQ(plan.margin, 48);  // 5 R + 4 = 34, rounded up to 16
  EXPECT_EQ(plan.core, 32);
  EXPECT_EQ(plan.slabs, 6);
  const ChunkRun run = run_chunked(scan, o, plan);
  expect_same_labels(whole, run);
  EXPECT_EQ(run.res.pass1_reads, 1);
}

// Grains of different brightness (grain_levels.hpp): each slab levelled
// from the slices beyond it, the decisions again on the levelled histograms
// (a third read of pass 1): the whole volume's levelled labels.
TEST(SegmentChunked, SameLabelsWithGrainsOfDifferentBrightness) {
  const auto s = test::grid_of_balls(
      4, 21, 9, [](int b) { return b % 5 == 0; },
      [](int b) { return std::array<double, 3>{0.35, 0.6, 1.0}[size_t(b % 3)]; }, 5);
  SegmentOptions o;
  o.grain_radius_vox = 9;
  const SegmentResult whole = segment(s.grey, o);
  ASSERT_TRUE(whole.grain_levels.used);
  ChunkPlan plan;
  plan.in_memory = false;
  plan.core = 32;
  plan.margin = 48;
  const ChunkRun run = run_chunked(s.grey, o, plan);
  EXPECT_TRUE(run.res.result.grain_levels.used);
  EXPECT_EQ(run.res.pass1_reads, 2);
  EXPECT_EQ(run.res.result.grain_levels.voxels_raised, whole.grain_levels.voxels_raised);
  expect_same_labels(whole, run);
}

// The field of view detected slab by slab (FovScan: two reads of pass 1),
// and 16-slice cores: still the whole volume's labels.
TEST(SegmentChunked, SameLabelsWithFieldOfView) {
  const auto scan = chunk_scan(true);
  const SegmentOptions o = chunk_options();
  const SegmentResult whole = segment(scan, o);
  ASSERT_TRUE(whole.fov.active);
  ChunkedOptions co;
  co.memory_limit_bytes = limit_for(scan.shape(), 16, 48);
  const ChunkPlan plan = plan_chunks(scan.shape(), o.grain_radius_vox, co);
  EXPECT_EQ(plan.slabs, 12);
  const ChunkRun run = run_chunked(scan, o, plan);
  EXPECT_EQ(run.res.pass1_reads, 2);
  EXPECT_TRUE(run.res.result.fov.active);
  EXPECT_DOUBLE_EQ(run.res.result.fov.radius, whole.fov.radius);
  expect_same_labels(whole, run);
}

// Anisotropic voxels (z edge 1.25 x the slice's): the distance map's
// spacing, and its float rounding, are the same in a slab as in the whole.
TEST(SegmentChunked, SameLabelsAnisotropic) {
  auto scan = chunk_scan(false);
  scan.set_geometry(Geometry{{37.5e-6, 30e-6, 30e-6}, {0, 0, 0}});
  const SegmentOptions o = chunk_options();
  const SegmentResult whole = segment(scan, o);
  ChunkedOptions co;
  co.memory_limit_bytes = limit_for(scan.shape(), 32, 48);
  const ChunkRun run = run_chunked(scan, o, plan_chunks(scan.shape(), o.grain_radius_vox, co));
  expect_same_labels(whole, run);
}

// The field of view found from three slabs is the one found on the whole volume.
TEST(SegmentChunked, FovScanBySlabs) {
  const auto scan = chunk_scan(true);
  const FieldOfView whole = find_field_of_view(scan, {});
  ASSERT_TRUE(whole.active);
  FovScan fs(scan.shape().ny, scan.shape().nx);
  const int64_t sl = scan.shape().slice_voxels();
  for (int64_t z0 : {0, 50, 130}) {
    const int64_t nz = z0 == 0 ? 50 : z0 == 50 ? 80 : 62;
    Volume<uint16_t> v(Shape{nz, scan.shape().ny, scan.shape().nx});
    std::copy(scan.data() + z0 * sl, scan.data() + (z0 + nz) * sl, v.data());
    fs.add(v);
  }
  const FieldOfView parts = fs.finish(scan.shape());
  ASSERT_TRUE(parts.active);
  EXPECT_EQ(parts.centre_y, whole.centre_y);
  EXPECT_EQ(parts.centre_x, whole.centre_x);
  EXPECT_EQ(parts.radius, whole.radius);
  EXPECT_EQ(parts.x0, whole.x0);
  EXPECT_EQ(parts.x1, whole.x1);
  EXPECT_EQ(parts.outside_voxels, whole.outside_voxels);
}

// A limit below one slab of 16 core slices and its margins: UsageError
// (exit 2) naming the limit and what one slab needs.
TEST(SegmentChunked, LimitTooSmallForOneSlab) {
  const Shape s{192, 64, 64};
  ChunkedOptions co;
  co.memory_limit_bytes = limit_for(s, 16, 48) - 2 * int64_t(ChunkedOptions{}.bytes_per_voxel * double(s.slice_voxels()));
  try {
    plan_chunks(s, 6.0, co);
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--memory-limit"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("too small for one slab"), std::string::npos) << e.what();
  }
  co.memory_limit_bytes += 2 * int64_t(ChunkedOptions{}.bytes_per_voxel * double(s.slice_voxels()));
  EXPECT_EQ(plan_chunks(s, 6.0, co).core, 16);
  // Under the in-memory estimate: no slabs.
  co.memory_limit_bytes = int64_t(ChunkedOptions{}.bytes_per_voxel * double(s.voxels())) + kSegmentFixedBytes;
  EXPECT_TRUE(plan_chunks(s, 6.0, co).in_memory);
}

// No margin: particles crossing a core's top are cut by the slab's face,
// which the ownership check reports (UsageError naming the options).
TEST(SegmentChunked, MarginTooSmallIsAnError) {
  const auto scan = chunk_scan(false);
  ChunkedOptions co;
  co.margin_vox = 0;
  co.memory_limit_bytes = limit_for(scan.shape(), 32, 0);
  const ChunkPlan plan = plan_chunks(scan.shape(), 6.0, co);
  ASSERT_EQ(plan.margin, 0);
  try {
    run_chunked(scan, chunk_options(), plan);
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--slab-margin-vox"), std::string::npos) << e.what();
  }
}

// Only ThresholdMethod::local needs the volume: refused, not approximated.
TEST(SegmentChunked, LocalThresholdRefused) {
  SegmentOptions o = chunk_options();
  o.threshold = ThresholdMethod::local;
  EXPECT_THROW(decide_grey({}, std::vector<int64_t>(65536, 1), {}, o), UsageError);
}

}  // namespace tg

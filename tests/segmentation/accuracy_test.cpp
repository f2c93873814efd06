#include "segmentation/accuracy.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "core/io/hdf5.hpp"
#include "data_synth/scene.hpp"
#include "segmentation/segment.hpp"

namespace tg {
namespace {

namespace fs = std::filesystem;

Volume<uint32_t> labels_1d(std::vector<uint32_t> v) {
  Volume<uint32_t> out(Shape{1, 1, int64_t(v.size())});
  std::copy(v.begin(), v.end(), out.begin());
  return out;
}

TEST(Accuracy, HandCountedCases) {
  const auto t = labels_1d({1, 1, 1, 1, 0, 2, 2, 2, 2, 0, 3, 3});
  const auto same = evaluate_labels(t, t);
  EXPECT_EQ(same.matched, 3);
  EXPECT_DOUBLE_EQ(same.f1, 1.0);
  // Grain 1 split 3 + 1 (over-segmented, still matched), 2 and 3 merged.
  const auto p = labels_1d({5, 5, 5, 6, 0, 7, 7, 7, 7, 0, 7, 7});
  const auto a = evaluate_labels(t, p);
  EXPECT_EQ(a.n_true, 3);
  EXPECT_EQ(a.n_pred, 3);
  EXPECT_DOUBLE_EQ(a.best_iou[1], 0.75);
  EXPECT_EQ(a.over_segmented, 1);
  EXPECT_EQ(a.under_segmenting, 1);
  EXPECT_EQ(a.match_of[1], 5u);              // IoU 3/4
  EXPECT_EQ(a.match_of[2], 7u);              // IoU 4/6
  EXPECT_EQ(a.match_of[3], 0u);              // IoU 2/6
  EXPECT_DOUBLE_EQ(a.f1, 2.0 * 2 / 6);
  // Leaving out particles and labels below 3 voxels: label 6 and nothing else.
  const auto b = evaluate_labels(t, p, {3});
  EXPECT_EQ(b.n_pred, 2);
  EXPECT_EQ(b.over_segmented, 0);
}

// One loading stage of the data_synth zeolite specimen, cropped at 30 um
// voxels (grain radius 22.7 voxels: the issue's >= 20-voxel regime), with
// blur, noise and intra-granular pores; `broken` of the grains split into
// halves, multi-fragments and chips 1.5 voxels apart.
struct SynthScan {
  Volume<uint16_t> grey;
  Volume<uint32_t> truth;
  Table table;
};

// Both stages come from one run (one packing: the slow part). ctest runs
// each TEST in its own process, so both checks live in one TEST below.
std::vector<SynthScan> make_scans(uint64_t seed) {
  {
    auto scene = synth::preset_scene("zeolite-stages");
    scene.voxel_um = 30;
    scene.size = 144;
    scene.seed = seed;
    scene.stage.strains = {0.0, 0.1548};
    scene.stage.broken = {0.0, 0.7};
    const fs::path dir = fs::temp_directory_path() / ("tg_seg_acc_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    synth::run_synth(scene, (dir / "s.h5").string(), false);
    std::vector<SynthScan> v;
    for (int st = 0; st < 2; ++st) {
      H5Reader r((dir / ("s_stage" + std::to_string(st) + ".h5")).string());
      v.push_back({std::get<Volume<uint16_t>>(r.read_volume("/volume")),
                   std::get<Volume<uint32_t>>(r.read_volume("/labels")), r.read_table("/truth")});
    }
    fs::remove_all(dir);
    return v;
  }
}

SegmentOptions zeolite_options() {
  SegmentOptions o;
  o.grain_radius_vox = 680.0 / 30.0;  // D50 1.36 mm at 30 um
  return o;
}

// Counted particles: at least the study's smallest measurable grain, 0.2 mm
// across, i.e. (pi/6) (200/30)^3 = 155 voxels (slivers cut by the crop fall below).
const AccuracyOptions kCounted{155};

// Tuning and asserting (docs/testing.md). The defaults of SegmentOptions
// (marker depth h = 0.7, pore filter, merge ratio) were tuned on seed 11 of
// this scene: F1 0.989 intact / 0.980 broken (segmentation/segment.hpp).
// The bounds are asserted on seeds 12 and 13, which no parameter was chosen
// on. Recorded there (issue 25): intact F1 0.9927 / 0.9774, broken F1
// 0.9965 / 0.9963, split halves 5/5 and 6/6, over-segmented intact grains
// 0 / 1 (seed 13: one grain of 66 split at a pore; the tuning seed had none).
// Asserted: F1 0.02 below the lower recorded figure (the two seeds differ by
// 0.015), at most 2 % of the intact grains over-segmented.
constexpr double kIntactBound = 0.9774 - 0.02, kBrokenBound = 0.9963 - 0.02;

void intact_porous_grains_are_found_once_each(const SynthScan& s, double f1_bound) {
  const auto res = segment(s.grey, zeolite_options());
  const auto a = evaluate_labels(s.truth, res.labels, kCounted);
  std::printf("intact: true %lld, labels %lld, F1 %.4f, over %lld, under %lld, median volume error %.4f, pores filled %lld\n",
              (long long)a.n_true, (long long)a.n_pred, a.f1, (long long)a.over_segmented,
              (long long)a.under_segmenting, a.median_volume_error, (long long)res.pores.filled);
  EXPECT_GE(a.f1, f1_bound);
  EXPECT_LE(double(a.over_segmented), 0.02 * double(a.n_true));  // pore-induced splits: rare
  EXPECT_GT(res.pores.filled, 0);
  EXPECT_LT(std::abs(a.median_volume_error), 0.03);
}

void split_halves_are_recovered_as_two_particles(const SynthScan& s, double f1_bound) {
  const auto res = segment(s.grey, zeolite_options());
  const auto a = evaluate_labels(s.truth, res.labels, kCounted);
  // Pairs of halves of one parent, both inside the field of view.
  const auto& id = s.table.num("id");
  const auto& parent = s.table.num("parent");
  const auto& cropped = s.table.num("cropped");
  const auto& kind = s.table.text("kind");
  std::map<int64_t, std::vector<uint32_t>> halves;
  for (int64_t r = 0; r < s.table.rows(); ++r)
    if (kind[size_t(r)] == "half" && cropped[size_t(r)] == 0) halves[int64_t(parent[size_t(r)])].push_back(uint32_t(id[size_t(r)]));
  int pairs = 0, recovered = 0;
  for (const auto& [p, ids] : halves) {
    if (ids.size() != 2 || ids[0] >= a.match_of.size() || ids[1] >= a.match_of.size()) continue;
    ++pairs;
    const uint32_t m0 = a.match_of[ids[0]], m1 = a.match_of[ids[1]];
    recovered += m0 && m1 && m0 != m1;
  }
  std::printf("broken: true %lld, labels %lld, F1 %.4f, over %lld, under %lld, split halves %d/%d\n",
              (long long)a.n_true, (long long)a.n_pred, a.f1, (long long)a.over_segmented,
              (long long)a.under_segmenting, recovered, pairs);
  ASSERT_GE(pairs, 3);
  EXPECT_GE(double(recovered), 0.9 * pairs);
  EXPECT_GE(a.f1, f1_bound);
}

TEST(SynthAccuracy, ZeoliteIntactAndBrokenStages) {
  for (uint64_t seed : {12u, 13u}) {
    SCOPED_TRACE("seed " + std::to_string(seed) + " (not a tuning seed)");
    const auto scans = make_scans(seed);
    {
      SCOPED_TRACE("intact stage: F1 bound, no pore-induced over-segmentation");
      intact_porous_grains_are_found_once_each(scans[0], kIntactBound);
    }
    {
      SCOPED_TRACE("broken stage: F1 bound, >= 90 % of split halves as two particles");
      split_halves_are_recovered_as_two_particles(scans[1], kBrokenBound);
    }
  }
}

}  // namespace
}  // namespace tg

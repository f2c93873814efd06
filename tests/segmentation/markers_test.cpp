#include "segmentation/markers.hpp"

#include <gtest/gtest.h>

#include <set>

#include "core/errors.hpp"
#include "fixtures.hpp"
#include "segmentation/distance_transform.hpp"

namespace tg {
namespace {

using test::draw_ball;

uint32_t markers_of(const Volume<uint8_t>& m, double h, Volume<uint32_t>& mk) {
  Volume<float> d;
  distance_transform(m, d);
  return find_markers(d, m, mk, {h, 26});
}

TEST(Markers, OneMarkerPerBallDespitePlateaus) {
  auto m = Volume<uint8_t>::filled(Shape{30, 30, 30}, 0);
  draw_ball(m, 14.5, 14.5, 14.5, 11);  // centre between voxels: an 8-voxel top plateau
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 1.0, mk), 1u);
  EXPECT_EQ(mk(14, 14, 14), 1u);
  EXPECT_EQ(mk(15, 15, 15), 1u);
}

TEST(Markers, TouchingPairDependsOnDepth) {
  // Balls of radius 10, centres 18 apart: neck radius sqrt(100 - 81) ~ 4.4,
  // so each peak has a dynamic of about 10 - 4.4 ~ 5.6 (voxelised: ~5-6).
  auto m = Volume<uint8_t>::filled(Shape{26, 26, 44}, 0);
  draw_ball(m, 12.5, 12.5, 12.5, 10);
  draw_ball(m, 12.5, 12.5, 30.5, 10);
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 2.0, mk), 2u);
  EXPECT_NE(mk(12, 12, 12), mk(12, 12, 30));
  EXPECT_EQ(markers_of(m, 8.0, mk), 1u);  // deeper than the neck: one grain
}

TEST(Markers, SplitHalvesOneVoxelApartKeepTwoMarkers) {
  // The usual min-distance rule (~ one radius) would keep one of these two peaks.
  auto m = Volume<uint8_t>::filled(Shape{30, 30, 31}, 0);
  draw_ball(m, 15, 15, 15, 12);
  test::cut_slab_x(m, 15, 1);
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 100.0, mk), 2u);  // even an absurd depth cannot merge components
}

TEST(Markers, EveryComponentGetsOneIncludingSingleVoxels) {
  auto m = Volume<uint8_t>::filled(Shape{9, 9, 9}, 0);
  m(0, 0, 0) = 1;  // corner of the volume
  m(4, 4, 4) = 1;
  m(8, 8, 2) = 1;
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(m, 2.0, mk), 3u);
  std::set<uint32_t> got{mk(0, 0, 0), mk(4, 4, 4), mk(8, 8, 2)};
  EXPECT_EQ(got, (std::set<uint32_t>{1, 2, 3}));  // raster order
}

TEST(Markers, EmptyVolumeAndBadArguments) {
  Volume<uint32_t> mk;
  EXPECT_EQ(markers_of(Volume<uint8_t>::filled(Shape{4, 4, 4}, 0), 1.0, mk), 0u);
  Volume<float> d = Volume<float>::filled(Shape{2, 2, 2}, 1.f);
  EXPECT_THROW(find_markers(d, Volume<uint8_t>::filled(Shape{2, 2, 3}, 1), mk), UsageError);
  EXPECT_THROW(find_markers(d, Volume<uint8_t>::filled(Shape{2, 2, 2}, 1), mk, {-1.0, 26}), UsageError);
}

}  // namespace
}  // namespace tg

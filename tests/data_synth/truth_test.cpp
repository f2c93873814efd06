#include "data_synth/truth.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "data_synth/render.hpp"

using namespace tg::synth;

TEST(Truth, ColumnsAgreeWithGeometryAndLabels) {
  std::vector<Particle> ps{make_grain(1, {15.2, 14.7, 15.9}, 8.3),
                           make_cap(2, Kind::half, 9, {{15, 15, 34}, 7}, {0, 1, 0}, 0.5),
                           make_grain(3, {2.0, 40.0, 40.0}, 4.0)};  // cut by the border
  const tg::Geometry g{{2e-5, 2e-5, 2e-5}, {1e-3, -2e-3, 0}};
  const tg::Shape shape{30, 48, 48};
  const Rendered r = render(ps, shape, g);
  const tg::Table t = truth_table(ps, r.labels, shape, g);
  ASSERT_EQ(t.rows(), 3);
  for (const char* c : {"id", "parent", "cz_vox", "cy_vox", "cx_vox", "radius_vox", "volume_vox", "cz_mm", "cy_mm",
                        "cx_mm", "radius_mm", "volume_mm3", "dmax_mm", "label_voxels", "cropped"})
    EXPECT_TRUE(t.has(c)) << c;
  EXPECT_EQ(t.text("kind")[1], "half");
  EXPECT_EQ(t.num("parent")[1], 9);
  const double v0 = 4.0 / 3.0 * std::numbers::pi * std::pow(8.3, 3);
  EXPECT_NEAR(t.num("volume_vox")[0], v0, 1e-9 * v0);
  // Physical twins: mm = 1e3·origin + voxel_mm · voxel coordinate.
  EXPECT_NEAR(t.num("cz_mm")[0], 1.0 + 0.02 * 15.2, 1e-12);
  EXPECT_NEAR(t.num("cy_mm")[0], -2.0 + 0.02 * 14.7, 1e-12);
  EXPECT_NEAR(t.num("volume_mm3")[0], v0 * 8e-6, 1e-9 * v0 * 8e-6);
  EXPECT_NEAR(t.num("radius_mm")[1], 0.14, 1e-12);
  // Labels: counted from the volume, and close to the volume for a sphere inside.
  int64_t n1 = 0;
  for (uint32_t l : r.labels.span()) n1 += l == 1;
  EXPECT_EQ(t.num("label_voxels")[0], static_cast<double>(n1));
  EXPECT_NEAR(n1, v0, 0.02 * v0);
  EXPECT_EQ(t.num("cropped")[0], 0);
  EXPECT_EQ(t.num("cropped")[2], 1);
}

TEST(Truth, NoPhysicalColumnsWithoutVoxelSize) {
  std::vector<Particle> ps{make_grain(1, {5, 5, 5}, 2)};
  const tg::Table t = truth_table(ps, {}, tg::Shape{10, 10, 10}, {});
  EXPECT_FALSE(t.has("cz_mm"));
  EXPECT_EQ(t.num("label_voxels")[0], 0);
}

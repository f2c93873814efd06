#include "dem/particles.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <set>
#include <string>

namespace tg::dem {
namespace {

TEST(Particles, FieldListCoversEveryVectorOnce) {
  Particles p;
  std::set<std::string> names;
  size_t bytes = 0;
  p.for_each_field([&](std::string_view n, auto& v) {
    names.insert(std::string(n));
    bytes += sizeof(v);
  });
  EXPECT_EQ(names.size(), 31u);
  // Every member of Particles is a std::vector listed in for_each_field:
  // a field added to the struct but not to the list changes the size.
  EXPECT_EQ(bytes, sizeof(Particles));
}

TEST(Particles, AppendCopyResize) {
  Particles p;
  p.append_sphere(1, 2, 3, 0.5e-3, 2000, 7, 0, kFlagBreakable);
  const int64_t i = p.append_sphere(0, 0, 0, 1e-3, 2000, 8);
  EXPECT_EQ(p.size(), 2);
  EXPECT_NEAR(p.m[i], 2000 * 4.0 / 3.0 * std::numbers::pi * 1e-9, 1e-18);
  EXPECT_DOUBLE_EQ(p.inertia[i], 0.4 * p.m[i] * 1e-6);
  p.vx[0] = 3;
  p.copy_sphere(0, 1);
  EXPECT_EQ(p.particle[1], 7);
  EXPECT_EQ(p.previous_particle[1], 7);  // a split's spheres inherit their mother's lineage
  EXPECT_EQ(p.vx[1], 3);
  EXPECT_EQ(p.r[1], 0.5e-3);
  p.resize(1);
  p.for_each_field([](std::string_view, const auto& v) { EXPECT_EQ(v.size(), 1u); });
}

}  // namespace
}  // namespace tg::dem

#include "core/volume.hpp"
#include "core/memory.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>

namespace tg {

TEST(Volume, LayoutIsContiguousInX) {
  Volume<uint16_t> v(Shape{2, 3, 4});
  for (int64_t i = 0; i < v.size(); ++i) v[i] = static_cast<uint16_t>(i);
  EXPECT_EQ(v(1, 2, 3), 23);
  EXPECT_EQ(v(1, 0, 0), 12);
  EXPECT_EQ(&v(0, 0, 1) - &v(0, 0, 0), 1);
}

TEST(Volume, SubBoxViewSharesMemoryAndShiftsOrigin) {
  Volume<float> v = Volume<float>::filled(Shape{4, 5, 6}, 0.f, Geometry{{2e-6, 2e-6, 2e-6}, {1.0, 0.0, 0.0}});
  auto sub = v.sub(Box{1, 2, 3, Shape{2, 2, 2}});
  sub(1, 1, 1) = 7.f;
  EXPECT_EQ(v(2, 3, 4), 7.f);
  EXPECT_DOUBLE_EQ(sub.geometry().origin_m[0], 1.0 + 2e-6);
  EXPECT_DOUBLE_EQ(sub.geometry().origin_m[2], 3 * 2e-6);
  EXPECT_FALSE(sub.contiguous());
  EXPECT_TRUE(v.slice(2).contiguous());
  EXPECT_THROW(v.sub(Box{3, 0, 0, Shape{2, 1, 1}}), UsageError);
  const Volume<float> copy = to_volume(sub);
  EXPECT_EQ(copy.shape(), (Shape{2, 2, 2}));
  EXPECT_EQ(copy(1, 1, 1), 7.f);
}

TEST(Volume, CloneIsDeep) {
  Volume<uint8_t> a = Volume<uint8_t>::filled(Shape{1, 2, 2}, 3);
  Volume<uint8_t> b = a.clone();
  b[0] = 9;
  EXPECT_EQ(a[0], 3);
}

TEST(Volume, AllocationBeyondAvailableMemoryFailsClearly) {
  setenv("TOMOGRAIN_MEMORY_LIMIT", "1M", 1);
  try {
    Volume<uint16_t> v(Shape{256, 256, 256});  // 32 MiB (requests under 16 MiB are not checked)
    FAIL() << "expected ResourceError";
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find("256x256x256"), std::string::npos) << e.what();
  }
  unsetenv("TOMOGRAIN_MEMORY_LIMIT");
  EXPECT_THROW(Volume<uint16_t>(Shape{int64_t{1} << 40, 1 << 20, 1 << 20}), ResourceError);
}

TEST(Memory, ParseByteSize) {
  EXPECT_EQ(parse_byte_size("1073741824"), int64_t(1) << 30);
  EXPECT_EQ(parse_byte_size("16GiB"), int64_t(16) << 30);
  EXPECT_EQ(parse_byte_size("16G"), int64_t(16) << 30);
  EXPECT_EQ(parse_byte_size("16gb"), int64_t(16000000000));
  EXPECT_EQ(parse_byte_size("1.5 MiB"), int64_t(3) << 19);
  EXPECT_EQ(parse_byte_size("512B"), 512);
  EXPECT_EQ(parse_byte_size("2T"), int64_t(2) << 40);
  for (const char* bad : {"", "GiB", "-1G", "16 GiBs", "16X", "0", "nan"}) EXPECT_EQ(parse_byte_size(bad), -1) << bad;
}

TEST(Volume, EmptyVolumeIsValid) {
  Volume<uint16_t> v(Shape{0, 10, 10});
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(v.size(), 0);
}

}  // namespace tg

namespace tg {
namespace {

// Written over its own storage, each value must still come from the value
// it replaces: 4- and 2-byte elements to 1 byte, sizes across the rounds'
// bounds (1, r, r^2 ... and the parallel ones), against a plain copy.
TEST(Volume, ConvertInPlaceMatchesAConvertingCopy) {
  for (int64_t nx : {1, 3, 4, 5, 17, 70001}) {
    Volume<float> f(Shape{3, 1, nx});
    Volume<uint16_t> g(Shape{3, 1, nx});
    for (int64_t i = 0; i < f.size(); ++i) {
      f[i] = float((i * 7919) % 251) - 100.0f;
      g[i] = uint16_t((i * 104729) % 65536);
    }
    const Volume<float> f0 = f.clone();
    const Volume<uint16_t> g0 = g.clone();
    const float* fs = f.data();
    const Volume<uint8_t> a = std::move(f).convert_in_place<uint8_t>([](float v) -> uint8_t { return v > 0 ? uint8_t(v) : 0; });
    const Volume<uint8_t> b = std::move(g).convert_in_place<uint8_t>([](uint16_t v) -> uint8_t { return uint8_t(v >> 8); });
    EXPECT_EQ(static_cast<const void*>(a.data()), static_cast<const void*>(fs));
    EXPECT_TRUE(f.empty());
    ASSERT_EQ(a.shape(), f0.shape());
    for (int64_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i], f0[i] > 0 ? uint8_t(f0[i]) : 0) << "float " << i << " of " << a.size();
      ASSERT_EQ(b[i], uint8_t(g0[i] >> 8)) << "u16 " << i << " of " << b.size();
    }
  }
}

}  // namespace
}  // namespace tg

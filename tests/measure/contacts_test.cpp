// Contacts, coordination and fabric (measure/contacts.hpp): the small cases
// (tolerance, lens area, fabric formula, coordination, empty volumes). The
// scenes with exact truth at radius 20 are in contacts_scene_test.cpp
// (label `slow`: Release only).
#include "measure/contacts.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "core/errors.hpp"
#include "data_synth/geometry.hpp"
#include "data_synth/render.hpp"
#include "tests/measure/contact_scenes.hpp"
#include "tests/measure/shapes.hpp"

namespace tg::measure {
namespace {

using V3 = Eigen::Vector3d;
using test::cut_lines;
constexpr double kVoxel = 1e-5;


using test::angle_deg;

// Two spheres of radius 20 at centre distance 30: the interface is the
// radical plane's disc, area pi (20^2 - 15^2) = 549.8 voxel^2; voxels inside
// both go to the side of the plane they lie on. Random orientations and
// sub-voxel offsets (seeds 1-6). Face to face the estimator reads the disc
// (digitised perimeter only); with lines the rim annulus adds (header).
TEST(Contacts, AreaOfALensInterface) {
  const double R = 20, d = 30, truth = std::numbers::pi * (R * R - d * d / 4);
  double worst_face = 0, worst_line = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const V3 u = test::random_rotation(seed).col(0);
    const V3 c = V3::Constant(32) + test::random_offset(seed);
    const V3 c1 = c - u * d / 2, c2 = c + u * d / 2;
    auto v = Volume<uint32_t>::filled(Shape{64, 64, 64}, 0, Geometry::isotropic_m(kVoxel));
    for (int64_t k = 0; k < 64; ++k)
      for (int64_t j = 0; j < 64; ++j)
        for (int64_t i = 0; i < 64; ++i) {
          const V3 p(k + 0.5, j + 0.5, i + 0.5);
          const bool in1 = (p - c1).norm() <= R, in2 = (p - c2).norm() <= R;
          if (in1 || in2) v(k, j, i) = (in1 && (!in2 || (p - c).dot(u) < 0)) ? 1 : 2;
        }
    for (int lines = 0; lines < 2; ++lines) {
      const auto lab = lines ? cut_lines(v) : v.clone();
      const auto r = find_contacts(lab.view());
      ASSERT_EQ(r.contacts.size(), 1u);
      const Contact& ct = r.contacts[0];
      EXPECT_LE(angle_deg(ct.normal, u), 2.0);
      EXPECT_LE((ct.point_m / kVoxel - c).norm(), lines ? 1.5 : 1.0);  // lines: one-sided, see the file header
      const double err = ct.area_m2 / (kVoxel * kVoxel) / truth - 1;
      (lines ? worst_line : worst_face) = std::max(lines ? worst_line : worst_face, std::abs(err));
      EXPECT_EQ(ct.face_to_face, lines == 0);
    }
  }
  if (std::getenv("TG_DEBUG")) std::printf("lens area worst |err|: face %.4f lines %.4f\n", worst_face, worst_line);
  EXPECT_LE(worst_face, 0.05);
  EXPECT_LE(worst_line, 0.25);
  RecordProperty("worst_face", std::to_string(worst_face));
  RecordProperty("worst_line", std::to_string(worst_line));
}

// Particles one void voxel apart along an axis touch (a line's width); two
// voxels apart they do not; a diagonal neighbour through three void voxels
// along every axis touches (a diagonal line is that thick).
TEST(Contacts, DetectionToleranceIsOneLine) {
  auto v = Volume<uint32_t>::filled(Shape{12, 12, 40}, 0, Geometry::isotropic_m(kVoxel));
  auto block = [&](uint32_t l, int64_t i0, int64_t i1) {
    for (int64_t k = 2; k < 10; ++k)
      for (int64_t j = 2; j < 10; ++j)
        for (int64_t i = i0; i < i1; ++i) v(k, j, i) = l;
  };
  block(1, 2, 10);
  block(2, 11, 19);  // one void voxel after label 1
  block(3, 21, 29);  // two void voxels after label 2
  block(4, 29, 37);  // face to face with label 3
  const auto r = find_contacts(v.view());
  ASSERT_EQ(r.contacts.size(), 2u);
  EXPECT_EQ(r.contacts[0].a, 1u);
  EXPECT_EQ(r.contacts[0].b, 2u);
  EXPECT_NEAR(r.contacts[0].normal[2], 1.0, 1e-12);
  EXPECT_NEAR(r.contacts[0].area_m2, 64 * kVoxel * kVoxel, 1e-18);
  EXPECT_FALSE(r.contacts[0].face_to_face);
  EXPECT_EQ(r.contacts[1].a, 3u);
  EXPECT_EQ(r.contacts[1].b, 4u);
  EXPECT_TRUE(r.contacts[1].face_to_face);
  EXPECT_NEAR(r.contacts[1].point_m[2] / kVoxel, 29.0, 1e-9);
  EXPECT_NEAR(r.contacts[1].point_m[0] / kVoxel, 6.0, 1e-9);
}

TEST(Contacts, FabricOfKnownNormals) {
  // Isotropic set (the 3 axes) -> N = I/3, a = 0; all along z -> a = 7.5
  // (sqrt(3/2) * 15/2 * sqrt(2/3)); normals' sign does not matter.
  std::vector<V3> iso{V3::UnitZ(), -V3::UnitY(), V3::UnitX()};
  const Fabric f = fabric(iso);
  EXPECT_NEAR((f.N - Eigen::Matrix3d::Identity() / 3).norm(), 0, 1e-15);
  EXPECT_NEAR(f.anisotropy, 0, 1e-14);
  std::vector<V3> z{V3(1, 0, 0), V3(-1, 0, 0)};  // (z, y, x): along z
  const Fabric g = fabric(z);
  EXPECT_NEAR(g.anisotropy, 7.5, 1e-12);
  EXPECT_NEAR(std::abs(g.major_axis[0]), 1, 1e-12);
  EXPECT_TRUE(std::isnan(fabric({}).anisotropy));
}

TEST(Contacts, CoordinationCountsBothEnds) {
  std::vector<Contact> c(3);
  c[0].a = 1; c[0].b = 2;
  c[1].a = 1; c[1].b = 5;
  c[2].a = 2; c[2].b = 5;
  const std::vector<uint32_t> labels{5, 1, 2, 9};
  EXPECT_EQ(coordination(c, labels), (std::vector<int>{2, 2, 2, 0}));
}

TEST(Contacts, EmptyAndSingleLabelVolumes) {
  auto v = Volume<uint32_t>::filled(Shape{4, 4, 4}, 0, Geometry::isotropic_m(kVoxel));
  EXPECT_TRUE(find_contacts(v.view()).contacts.empty());
  v(1, 1, 1) = 7;
  EXPECT_TRUE(find_contacts(v.view()).contacts.empty());
  v(1, 1, 2) = 8;  // two single voxels face to face
  const auto r = find_contacts(v.view());
  ASSERT_EQ(r.contacts.size(), 1u);
  EXPECT_NEAR(r.contacts[0].normal[2], 1, 1e-12);
  auto none = Volume<uint32_t>::filled(Shape{4, 4, 4}, 0);
  EXPECT_THROW(find_contacts(none.view()), UsageError);
}

}  // namespace
}  // namespace tg::measure

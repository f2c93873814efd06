#include "dem/breakage/splitting_plane.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Geometry>

using namespace tg::dem;
using namespace tg::dem::breakage;

namespace {
constexpr double kGrainR = 5e-4;
const double kGrainV = 4.0 / 3.0 * std::numbers::pi * kGrainR * kGrainR * kGrainR;

// A pair of opposite inward forces of magnitude f on the sphere at ±R·axis.
void push_pair(std::vector<ContactLoad>& c, Vec3 axis, double f) {
  c.push_back({kGrainR * axis, -f * axis});
  c.push_back({-kGrainR * axis, f * axis});
}

Vec3 rotate(const Eigen::Matrix3d& q, Vec3 v) {
  const Eigen::Vector3d r = q * Eigen::Vector3d(v.x, v.y, v.z);
  return {r(0), r(1), r(2)};
}
}  // namespace

// Diametral compression along z (10 N), confinement 2 N along x and 5 N
// along y: σzz = 2 F R / V, σ3 along x (least compressed), the plane
// contains z and opens along x.
TEST(SplittingPlane, DiametralCompressionOpensAlongLeastConfinedAxis) {
  std::vector<ContactLoad> c;
  push_pair(c, {0, 0, 1}, 10);
  push_pair(c, {1, 0, 0}, 2);
  push_pair(c, {0, 1, 0}, 5);
  const auto p = splitting_plane({0, 0, 0}, kGrainV, c);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->rule, PlaneRule::kSigma3);
  EXPECT_EQ(p->contact, 0);
  EXPECT_DOUBLE_EQ(p->f_max, 10);
  EXPECT_NEAR(p->n_f.z, 1, 1e-15);
  // Compression positive: σ1 = σzz = 2·10·R/V, σ2 = σyy, σ3 = σxx.
  EXPECT_NEAR(p->principal(2), 2 * 10 * kGrainR / kGrainV, 1e-9 * p->principal(2));
  EXPECT_NEAR(p->principal(1), 2 * 5 * kGrainR / kGrainV, 1e-9 * p->principal(2));
  EXPECT_NEAR(p->principal(0), 2 * 2 * kGrainR / kGrainV, 1e-9 * p->principal(2));
  EXPECT_NEAR(p->normal.x, 1, 1e-12);
  EXPECT_NEAR(std::abs(p->normal.y) + std::abs(p->normal.z), 0, 1e-12);
}

// Same load turned by an arbitrary rotation Q and shifted: the plane turns with it.
TEST(SplittingPlane, FollowsARotatedLoad) {
  const Eigen::Matrix3d q =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) * Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const Vec3 x0{1e-3, -2e-3, 4e-3};
  std::vector<ContactLoad> c;
  push_pair(c, rotate(q, {0, 0, 1}), 10);
  push_pair(c, rotate(q, {1, 0, 0}), 2);
  push_pair(c, rotate(q, {0, 1, 0}), 5);
  for (auto& l : c) l.point = l.point + x0;
  const auto p = splitting_plane(x0, kGrainV, c);
  ASSERT_TRUE(p);
  const Vec3 ex = rotate(q, {1, 0, 0});
  EXPECT_NEAR(std::abs(dot(p->normal, ex)), 1, 1e-9);
  EXPECT_NEAR(dot(p->normal, p->n_f), 0, 1e-12);  // the plane contains the largest force
  // Canonical sign: the largest component is positive.
  const double m = std::max({std::abs(p->normal.x), std::abs(p->normal.y), std::abs(p->normal.z)});
  EXPECT_TRUE(p->normal.x == m || p->normal.y == m || p->normal.z == m);
}

// Frictional contact: the largest NORMAL force decides, not the largest force.
TEST(SplittingPlane, LargestNormalForceNotLargestForce) {
  std::vector<ContactLoad> c;
  push_pair(c, {0, 0, 1}, 10);
  push_pair(c, {1, 0, 0}, 2);
  push_pair(c, {0, 1, 0}, 5);
  c.push_back({{kGrainR, 0, 0}, {-9, 0, 30}});  // 31 N in total, only 9 N normal
  const auto p = splitting_plane({0, 0, 0}, kGrainV, c);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->contact, 0);
}

// σ3 parallel to n_f: one pair of 10 N along z, but 2 × 8 N on each side
// along x and 2 × 6 N along y: σ3 = σzz ∥ n_f → the σ2 direction (y) opens.
TEST(SplittingPlane, Sigma3ParallelToForceUsesSigma2) {
  std::vector<ContactLoad> c;
  push_pair(c, {0, 0, 1}, 10);
  push_pair(c, {1, 0, 0}, 8);
  push_pair(c, {1, 0, 0}, 8);
  push_pair(c, {0, 1, 0}, 6);
  push_pair(c, {0, 1, 0}, 6);
  const auto p = splitting_plane({0, 0, 0}, kGrainV, c);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->rule, PlaneRule::kSigma2);
  EXPECT_NEAR(p->normal.y, 1, 1e-12);
}

// One grain between two platens: σ2 = σ3 = 0, n_f ∥ e1: the fixed-axis rule
// gives x (deterministic, documented).
TEST(SplittingPlane, PlatenCrushIsDegenerateAndPicksX) {
  std::vector<ContactLoad> c;
  push_pair(c, {0, 0, 1}, 10);
  const auto p = splitting_plane({0, 0, 0}, kGrainV, c);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->rule, PlaneRule::kFixedAxis);
  EXPECT_NEAR(p->normal.x, 1, 1e-15);
  // Platens along x instead: x is ∥ n_f, so the rule takes y.
  std::vector<ContactLoad> d;
  push_pair(d, {1, 0, 0}, 10);
  const auto q = splitting_plane({0, 0, 0}, kGrainV, d);
  ASSERT_TRUE(q);
  EXPECT_NEAR(q->normal.y, 1, 1e-15);
}

// σ2 = σ3 with n_f not along e1: four 3 N pairs along z (σ1 = 24 R/V), one
// 5 N pair along x and one along y (σ2 = σ3 = 10 R/V). The largest normal
// force is along x, every direction of the xy plane is a σ3 direction, and
// the one ⟂ n_f is e1 × n_f = ±y.
TEST(SplittingPlane, DoubleSigma3UsesCrossProduct) {
  std::vector<ContactLoad> c;
  push_pair(c, {1, 0, 0}, 5);
  push_pair(c, {0, 1, 0}, 5);
  for (int k = 0; k < 4; ++k) push_pair(c, {0, 0, 1}, 3);
  const auto p = splitting_plane({0, 0, 0}, kGrainV, c);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->contact, 0);
  EXPECT_EQ(p->rule, PlaneRule::kDegenerate);
  EXPECT_NEAR(p->normal.y, 1, 1e-12);
  // Uniaxial load off the axes: n_f ∥ e1, the fixed-axis rule projects x ⟂ n_f.
  std::vector<ContactLoad> d;
  const double a = 0.3;
  push_pair(d, {std::sin(a), 0, std::cos(a)}, 10);
  const auto q = splitting_plane({0, 0, 0}, kGrainV, d);
  ASSERT_TRUE(q);
  EXPECT_EQ(q->rule, PlaneRule::kFixedAxis);
  EXPECT_NEAR(dot(q->normal, q->n_f), 0, 1e-12);
  EXPECT_NEAR(q->normal.y, 0, 1e-12);
  EXPECT_NEAR(q->normal.x, std::cos(a), 1e-12);
}

TEST(SplittingPlane, IsotropicUsesFixedAxis) {
  std::vector<ContactLoad> c;
  push_pair(c, {0, 0, 1}, 10);
  push_pair(c, {1, 0, 0}, 10);
  push_pair(c, {0, 1, 0}, 10);
  const auto p = splitting_plane({0, 0, 0}, kGrainV, c);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->rule, PlaneRule::kFixedAxis);
  EXPECT_NEAR(p->principal(0), 2 * 10 * kGrainR / kGrainV, 1e-6 * p->principal(0));  // compression positive
  EXPECT_NEAR(p->normal.x, 1, 1e-15);
}

TEST(SplittingPlane, NoCompressiveContactGivesNothing) {
  std::vector<ContactLoad> c;
  EXPECT_FALSE(splitting_plane({0, 0, 0}, kGrainV, c));
  c.push_back({{kGrainR, 0, 0}, {1, 0, 0}});  // pulls outwards (adhesion-like)
  EXPECT_FALSE(splitting_plane({0, 0, 0}, kGrainV, c));
}

// Contact fabric in the comparison (compare/fabric.hpp): sphere packings
// whose fabric is known analytically, through the three ways compare gets
// contacts — the DEM's spheres (exact), the voxelised truth labels (ideal)
// and the segmented grey scan (imaged) — plus the polar histogram and the
// size classes on hand-countable inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "compare/comparison.hpp"
#include "compare/dem_stage.hpp"
#include "compare/fabric.hpp"
#include "compare/series.hpp"
#include "compare/voxelise.hpp"

namespace tg {
namespace {

constexpr double kVoxel = 1e-4;     // 0.1 mm
constexpr double kR = 8.3 * kVoxel; // radius 8.3 voxels: the spheres sit at different sub-voxel offsets

// n_xy × n_xy columns of n_z spheres of radius kR, tangent along z; columns
// `gap` apart (surface to surface) along x and y: gap 0 is the simple cubic
// lattice.
SphereTable lattice(int n_xy, int n_z, double gap) {
  SphereTable s;
  int64_t id = 0;
  for (int k = 0; k < n_z; ++k)
    for (int j = 0; j < n_xy; ++j)
      for (int i = 0; i < n_xy; ++i)
        s.push_back(i * (2 * kR + gap), j * (2 * kR + gap), kR + k * 2 * kR, kR, id++);
  return s;
}

// The labels' series (ideal, or imaged when `imaged`) of a voxelised sphere table, as compare measures it.
compare::Series labels_series(const SphereTable& s, bool imaged) {
  compare::VoxeliseOptions vo;
  vo.voxel_m = kVoxel;
  vo.grey = imaged;
  compare::Voxelised v = compare::voxelise(s, vo);
  compare::Series out;
  const auto po = compare::CompareOptions::default_measure();
  if (!imaged) {
    compare::measure_series(v.labels, po, out);
    return out;
  }
  SegmentOptions so;
  so.grain_radius_vox = kR / kVoxel;
  const SegmentResult r = segment(std::move(v.grey), so);
  compare::measure_series(r.labels, po, out);
  return out;
}

void expect_N(const Eigen::Matrix3d& N, const Eigen::Matrix3d& want, double tol) {
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(N(a, b), want(a, b), tol) << "N(" << a << "," << b << ")";
}

// Simple cubic, 4 x 4 x 4 tangent spheres: 3 x 16 x 3 = 144 contacts, as many
// along each axis, so N = I/3 and a = 0 exactly.
TEST(Fabric, SimpleCubicLattice) {
  const SphereTable s = lattice(4, 4, 0);
  const compare::ContactSeries exact = compare::exact_contact_series(s);
  ASSERT_TRUE(exact.measured);
  EXPECT_EQ(exact.fabric.contacts, 144);
  EXPECT_EQ(exact.contacts.rows(), 144);
  expect_N(exact.fabric.N, Eigen::Matrix3d::Identity() / 3, 1e-12);
  EXPECT_NEAR(exact.fabric.anisotropy, 0, 1e-12);
  EXPECT_NEAR(exact.near_axis_share, 48.0 / 144, 1e-12);
  // Polar angle 0 (z contacts) in the first band, 90 (x, y) in the last; 1/9 of isotropic normals per band.
  ASSERT_EQ(exact.polar.count.size(), static_cast<size_t>(compare::kPolarBands));
  EXPECT_EQ(exact.polar.count.front(), 48);
  EXPECT_EQ(exact.polar.count.back(), 96);
  EXPECT_NEAR(exact.polar.density.front(), 48.0 / 144 * 9, 1e-9);
  EXPECT_NEAR(exact.polar.density.back(), 96.0 / 144 * 9, 1e-9);
  // Coordination 3 (8 corners), 4 (24 edge), 5 (24 face), 6 (8 inside); one size,
  // so the quartiles go by coordination: {8x3, 8x4}, {16x4}, {16x5}, {8x5, 8x6}.
  ASSERT_EQ(exact.by_size.size(), 4u);
  const double want[4] = {3.5, 4, 5, 5.5};
  for (int q = 0; q < 4; ++q) {
    EXPECT_EQ(exact.by_size[q].particles, 16);
    EXPECT_NEAR(exact.by_size[q].mean_coordination, want[q], 1e-12);
    EXPECT_NEAR(exact.by_size[q].size_from, 2 * kR * 1e3, 1e-12);
  }
  EXPECT_NEAR(compare::mean_coordination(exact.by_size), 4.5, 1e-12);

  // The image method at R = 8.3 voxels: every contact found, none added; N
  // within 2e-3 of I/3 (measured: ideal exact to 1e-15 by the lattice's
  // symmetry, imaged 1.1e-4, a = 0.002).
  for (bool imaged : {false, true}) {
    SCOPED_TRACE(imaged ? "imaged" : "ideal");
    const compare::Series ls = labels_series(s, imaged);
    ASSERT_TRUE(ls.contacts.measured);
    EXPECT_EQ(ls.contacts.fabric.contacts, 144);
    expect_N(ls.contacts.fabric.N, Eigen::Matrix3d::Identity() / 3, 2e-3);
    EXPECT_LT(ls.contacts.fabric.anisotropy, 0.02);
  }
}

// Columns along z, 4 voxels apart sideways (more than one watershed line):
// every contact along z, N = diag(1, 0, 0), a = 7.5. The image method:
// measured N_zz 0.99999 (ideal), 0.99998 (imaged), |N_zy| <= 6e-4.
TEST(Fabric, ContactsOnlyAlongZ) {
  const SphereTable s = lattice(3, 4, 4 * kVoxel);
  const compare::ContactSeries exact = compare::exact_contact_series(s);
  EXPECT_EQ(exact.fabric.contacts, 27);
  Eigen::Matrix3d zz = Eigen::Matrix3d::Zero();
  zz(0, 0) = 1;
  expect_N(exact.fabric.N, zz, 1e-12);
  EXPECT_NEAR(exact.fabric.anisotropy, 7.5, 1e-12);
  EXPECT_NEAR(exact.near_axis_share, 1, 1e-12);
  for (bool imaged : {false, true}) {
    SCOPED_TRACE(imaged ? "imaged" : "ideal");
    const compare::Series ls = labels_series(s, imaged);
    EXPECT_EQ(ls.contacts.fabric.contacts, 27);
    expect_N(ls.contacts.fabric.N, zz, 2e-3);
    EXPECT_NEAR(ls.contacts.fabric.anisotropy, 7.5, 0.01);
    EXPECT_NEAR(ls.contacts.near_axis_share, 1, 1e-12);
  }
}

// A two-sphere fragment resting on a grain with both spheres: two exact
// contacts (the DEM's sphere pairs, normals along x and y), one touching
// particle each.
TEST(Fabric, ExactContactsAreSpherePairs) {
  SphereTable s;
  s.push_back(0, 0, 0, 2e-3, 7);        // the grain, id 7
  s.push_back(3e-3, 0, 0, 1e-3, 3);     // fragment id 3, touching along x
  s.push_back(0, 3e-3, 0, 1e-3, 3);     // and along y
  const compare::ContactSeries c = compare::exact_contact_series(s);
  ASSERT_EQ(c.fabric.contacts, 2);
  EXPECT_EQ(c.contacts.num("a"), (std::vector<double>{3, 3}));  // from the smaller id to the larger
  EXPECT_NEAR(c.fabric.N(2, 2), 0.5, 1e-15);  // (z, y, x): x and y share the two normals
  EXPECT_NEAR(c.fabric.N(1, 1), 0.5, 1e-15);
  EXPECT_NEAR(compare::mean_coordination(c.by_size), 1.0, 1e-15);
}

// Isotropic normals (a Fibonacci sphere): density 1 in every band of equal
// solid angle, 1 - cos 30 deg of them within 30 deg of z.
TEST(Fabric, IsotropicNormalsReadOne) {
  std::vector<Eigen::Vector3d> n;
  const int m = 20000;
  for (int q = 0; q < m; ++q) {
    const double z = 1 - (q + 0.5) * 2.0 / m, r = std::sqrt(1 - z * z), phi = q * std::numbers::pi * (3 - std::sqrt(5.0));
    n.emplace_back(z, r * std::sin(phi), r * std::cos(phi));
  }
  std::vector<std::pair<int64_t, int64_t>> pairs(n.size(), {1, 2});
  const compare::ContactSeries c = compare::contact_series(pairs, n);
  for (double d : c.polar.density) EXPECT_NEAR(d, 1, 2e-3);
  EXPECT_NEAR(c.near_axis_share, 1 - std::sqrt(3.0) / 2, 1e-3);
  EXPECT_NEAR(c.fabric.anisotropy, 0, 1e-3);
  const auto e = measure::equal_solid_angle_edges_deg(4);
  ASSERT_EQ(e.size(), 5u);
  EXPECT_NEAR(e[1], std::acos(0.75) * 180 / std::numbers::pi, 1e-12);
  EXPECT_EQ(e[4], 90.0);
}

// Size classes by hand: 5 particles in 4 classes take 1, 1, 1, 2 (floor cuts).
TEST(Fabric, CoordinationBySize) {
  const std::vector<double> size{5, 1, 3, 2, 4}, z{10, 2, 6, 4, 8};
  const auto c = measure::coordination_by_size(size, z);
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c[0].particles, 1);
  EXPECT_EQ(c[0].size_from, 1);
  EXPECT_EQ(c[0].mean_coordination, 2);
  EXPECT_EQ(c[3].particles, 2);
  EXPECT_EQ(c[3].size_from, 4);
  EXPECT_EQ(c[3].size_to, 5);
  EXPECT_EQ(c[3].mean_coordination, 9);
}

}  // namespace
}  // namespace tg

// Contacts, coordination and fabric (measure/contacts.hpp) against scenes
// whose contacts are known exactly (~1.4 s a seed in Release; label `slow`,
// so the ASan stage leaves them out).
//
// Scenes: spheres of radius 20-23 voxels grown one by one, each placed so
// that it overlaps one or two earlier spheres by 0.6 voxel along their line
// of centres (a contact, as between DEM spheres) and stays at least 3 voxels
// from every other sphere (not a contact): the truth has no ambiguous pairs,
// since the image method's tolerance is one watershed line (~1 voxel).
// Rendered with data_synth (partial volume; a voxel belongs to the sphere
// covering most of it, the earlier sphere on ties). "Lines" variants then
// cut a one-voxel, 26-separating watershed-style line between every two
// touching labels (the larger label gives up its voxels that touch a smaller
// one), the image `segment` produces.
// The normal's ball radius (6 vs 9 voxels) was chosen on seeds 3-5; the
// scene test asserts on seeds 1, 2 and 6 (7 and 8 also pass: |a - a_truth|
// <= 0.013, median normal error <= 0.5 deg in all ten runs). Set TG_DEBUG
// to print the errors.
#include "measure/contacts.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
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
using test::Scene;
using test::cut_lines;
constexpr double kSceneVoxel = 1e-5;

Scene grow_scene(int64_t n, unsigned seed, int target) { return test::grow_scene(n, seed, target); }
Volume<uint32_t> render_scene(const Scene& s, int64_t n) { return test::render_scene(s, n, kSceneVoxel); }

using test::angle_deg;

struct Score {
  int interior = 0, right = 0;
  double median_normal_err = 0, max_point_err = 0;
  double a_image = 0, a_truth = 0;
  int missed = 0, extra = 0;
};

Score score(const Scene& s, const Volume<uint32_t>& labels, int threads = 2) {
  ContactOptions o;
  o.threads = threads;
  const auto res = find_contacts(labels.view(), o);
  std::map<std::pair<uint32_t, uint32_t>, const Contact*> found;
  for (const auto& c : res.contacts) found[{c.a, c.b}] = &c;
  const int64_t n = labels.shape().nz;
  // Interior: the whole sphere at least a voxel inside the volume.
  auto interior = [&](size_t p) { return ((s.c[p].array() - s.r[p]) > 1).all() && ((s.c[p].array() + s.r[p]) < n - 1).all(); };
  std::vector<int> truth_z(s.c.size(), 0);
  std::vector<double> errs;
  std::vector<V3> nt, ni;
  Score sc;
  for (const auto& [p, q] : s.contacts) {
    ++truth_z[static_cast<size_t>(p)];
    ++truth_z[static_cast<size_t>(q)];
    const V3 nn = (s.c[q] - s.c[p]).normalized();  // from the smaller label to the larger
    const V3 point = s.c[p] + nn * (s.r[p] - 0.3);     // (half the overlap inside each)
    const bool seen = ((point.array() > 2) && (point.array() < n - 2)).all();
    if (seen) nt.push_back(nn);
    auto it = found.find({static_cast<uint32_t>(p + 1), static_cast<uint32_t>(q + 1)});
    if (it == found.end()) {
      sc.missed += seen;
      continue;
    }
    errs.push_back(angle_deg(it->second->normal, nn));
    const V3 pi = it->second->point_m / kSceneVoxel;
    sc.max_point_err = std::max(sc.max_point_err, (pi - point).norm());
  }
  for (const auto& c : res.contacts) {
    const bool in_truth = std::find(s.contacts.begin(), s.contacts.end(),
                                    std::pair<int, int>{static_cast<int>(c.a) - 1, static_cast<int>(c.b) - 1}) != s.contacts.end();
    sc.extra += !in_truth;
    const V3 pm = c.point_m / kSceneVoxel;
    if (((pm.array() > 2) && (pm.array() < n - 2)).all()) ni.push_back(c.normal);
  }
  std::vector<uint32_t> ids(s.c.size());
  for (size_t p = 0; p < ids.size(); ++p) ids[p] = static_cast<uint32_t>(p + 1);
  const auto z = coordination(res.contacts, ids);
  for (size_t p = 0; p < s.c.size(); ++p)
    if (interior(p)) {
      ++sc.interior;
      sc.right += z[p] == truth_z[p];
    }
  std::sort(errs.begin(), errs.end());
  if (std::getenv("TG_DEBUG")) {
    std::printf("contacts %zu truth %zu; errors:", res.contacts.size(), s.contacts.size());
    for (double e : errs) std::printf(" %.1f", e);
    std::printf("\n");
  }
  sc.median_normal_err = errs.empty() ? 180 : errs[errs.size() / 2];
  sc.a_image = fabric(ni).anisotropy;
  sc.a_truth = fabric(nt).anisotropy;
  if (std::getenv("TG_DEBUG")) std::printf("a %.4f truth %.4f diff %.4f median %.2f\n", sc.a_image, sc.a_truth, sc.a_image - sc.a_truth, sc.median_normal_err);
  return sc;
}

class ContactsScene : public ::testing::TestWithParam<unsigned> {};

// Radius 20-23 voxels, labels face to face and with watershed lines: the
// issue's bar (coordination right for >= 95 % of interior particles, median
// normal error <= 5 deg, fabric anisotropy within 0.02 of the truth's).
TEST_P(ContactsScene, CoordinationNormalsFabricRadius20) {
  const int64_t n = 176;
  const Scene s = grow_scene(n, GetParam(), 40);
  ASSERT_GE(s.contacts.size(), 25u);
  const auto plain = render_scene(s, n);
  for (int lines = 0; lines < 2; ++lines) {
    SCOPED_TRACE(lines ? "watershed lines" : "face to face");
    const Score sc = score(s, lines ? cut_lines(plain) : plain.clone());
    ASSERT_GE(sc.interior, 5);
    EXPECT_GE(sc.right, std::ceil(0.95 * sc.interior)) << sc.right << " of " << sc.interior;
    EXPECT_EQ(sc.missed, 0);
    EXPECT_EQ(sc.extra, 0);
    EXPECT_LE(sc.median_normal_err, 5.0);
    EXPECT_NEAR(sc.a_image, sc.a_truth, 0.02);
    // The test's lines lie wholly on the larger label's side: the interface
    // moves by up to ~1 voxel there (measured 1.8 at most), 0.6 face to face.
    EXPECT_LE(sc.max_point_err, lines ? 2.0 : 1.0);  // voxels
  }
}
INSTANTIATE_TEST_SUITE_P(Seeds, ContactsScene, ::testing::Values(1u, 2u, 6u));

TEST(Contacts, ThreadCountDoesNotChangeResults) {
  const int64_t n = 128;
  const Scene s = grow_scene(n, 7, 20);
  const auto labels = cut_lines(render_scene(s, n));
  ContactOptions o1, o2;
  o1.threads = 1;
  o2.threads = 2;
  const auto a = find_contacts(labels.view(), o1), b = find_contacts(labels.view(), o2);
  ASSERT_EQ(a.contacts.size(), b.contacts.size());
  ASSERT_GT(a.contacts.size(), 5u);
  for (size_t k = 0; k < a.contacts.size(); ++k) {
    EXPECT_EQ(a.contacts[k].a, b.contacts[k].a);
    EXPECT_EQ(a.contacts[k].b, b.contacts[k].b);
    EXPECT_EQ(a.contacts[k].area_m2, b.contacts[k].area_m2);
    EXPECT_EQ(a.contacts[k].normal, b.contacts[k].normal);
    EXPECT_EQ(a.contacts[k].point_m, b.contacts[k].point_m);
  }
}

}  // namespace
}  // namespace tg::measure

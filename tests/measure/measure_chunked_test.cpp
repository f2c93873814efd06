// The slab-by-slab particle table (measure_chunked.hpp) against the whole
// volume's (measure_particles): every column equal, not close.
#include "measure/measure_chunked.hpp"

#include "measure/contacts.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/errors.hpp"

namespace tg::measure {
namespace {

struct ChunkScene {
  Volume<uint32_t> labels;
  Volume<uint16_t> grey;
};

// Balls of radius 2-7 voxels at random (some cut by the faces, some
// touching), each a label drawn in index order; label 5 is given to a second
// ball far from its first one (a label in two pieces must add up too);
// anisotropic voxels; grey: partial occupancy from 4^3 sub-samples, plus
// noise.
ChunkScene chunk_scene(unsigned seed) {
  const Shape sh{37, 30, 33};
  Geometry g;
  g.voxel_size_m = {12e-6, 10e-6, 11e-6};
  g.origin_m = {1e-3, -2e-3, 0.5e-3};
  ChunkScene s{Volume<uint32_t>::filled(sh, 0, g), Volume<uint16_t>::filled(sh, 0, g)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  struct Ball { double z, y, x, r; uint32_t label; };
  std::vector<Ball> balls;
  for (uint32_t l = 1; l <= 24; ++l)
    balls.push_back({u(rng) * sh.nz, u(rng) * sh.ny, u(rng) * sh.nx, 2 + 5 * u(rng), l});
  balls.push_back({3.0, 4.0, 5.0, 3.0, 5});
  balls.push_back({33.0, 26.0, 28.0, 2.5, 5});
  std::normal_distribution<double> noise(0, 600);
  for (int64_t k = 0; k < sh.nz; ++k)
    for (int64_t j = 0; j < sh.ny; ++j)
      for (int64_t i = 0; i < sh.nx; ++i) {
        int inside = 0;
        for (int a = 0; a < 64; ++a) {
          const double z = k + (a / 16 + 0.5) / 4, y = j + (a / 4 % 4 + 0.5) / 4, x = i + (a % 4 + 0.5) / 4;
          for (const Ball& b : balls)
            if ((z - b.z) * (z - b.z) + (y - b.y) * (y - b.y) + (x - b.x) * (x - b.x) < b.r * b.r) {
              ++inside;
              break;
            }
        }
        const double c = k + 0.5, cy = j + 0.5, cx = i + 0.5;
        for (const Ball& b : balls)
          if ((c - b.z) * (c - b.z) + (cy - b.y) * (cy - b.y) + (cx - b.x) * (cx - b.x) < b.r * b.r) {
            s.labels(k, j, i) = b.label;
            break;
          }
        s.grey(k, j, i) = uint16_t(std::clamp(10000.0 + 20000.0 * inside / 64.0 + noise(rng), 1.0, 65535.0));
      }
  return s;
}

// Slices [z0, z0 + nz) of a volume: what an HDF5 slab reader returns.
template <class T>
Volume<T> chunk_slices(const Volume<T>& whole, int64_t z0, int64_t nz) {
  const Shape sh = whole.shape();
  Volume<T> v = Volume<T>::filled({nz, sh.ny, sh.nx}, 0, whole.geometry());
  for (int64_t k = 0; k < nz; ++k)
    for (int64_t j = 0; j < sh.ny; ++j)
      for (int64_t i = 0; i < sh.nx; ++i) v(k, j, i) = whole(z0 + k, j, i);
  return v;
}

ParticleOptions chunk_options(bool grey_levels, bool box = false) {
  ParticleOptions o;
  o.contacts = !box;  // the coordination column (contacts in two passes); the box run leaves it out
  o.oriented_box = box;  // CGAL's box: ~100x the calipers' cost, so in one run only
  o.convex = true;
  if (grey_levels) {
    o.grey_levels.void_grey = 10000;
    o.grey_levels.solid_grey = 30000;
  }
  return o;
}

void expect_same_tables(const std::vector<Particle>& a, const std::vector<Particle>& b, const std::string& what) {
  const Table ta = particle_table(a), tb = particle_table(b);
  ASSERT_EQ(ta.rows(), tb.rows()) << what;
  ASSERT_EQ(ta.columns().size(), tb.columns().size()) << what;
  for (const auto& c : ta.columns()) {
    if (c.is_text) continue;
    const auto& other = tb.num(c.name);
    // The convex volume sums tetrahedra over CGAL's triangulation of the
    // hull's coplanar facets, which follows CGAL's random state (the call
    // history), not the points: equal to rounding only (particles.hpp).
    const double tol = c.name == "convex_volume_mm3" || c.name == "solidity" ? 1e-12 : 0.0;
    for (size_t r = 0; r < c.num.size(); ++r)
      ASSERT_NEAR(c.num[r], other[r], tol * std::abs(c.num[r])) << what << ": column " << c.name << ", row " << r;
  }
}

TEST(MeasureChunked, SlabsGiveTheWholeVolumesTable) {
  const ChunkScene s = chunk_scene(7);
  ParticleOptions whole = chunk_options(true);
  const VolumeView<const uint16_t> gv = s.grey.view();
  whole.grey = &gv;
  const auto ref = measure_particles(s.labels.view(), whole);
  ASSERT_GE(ref.size(), 20u);
  const Shape sh = s.labels.shape();
  auto labels = [&](int64_t z0, int64_t nz) { return chunk_slices(s.labels, z0, nz); };
  Volume<uint16_t> grey_buf;
  auto grey = [&](int64_t z0, int64_t nz) -> const Volume<uint16_t>& {
    grey_buf = chunk_slices(s.grey, z0, nz);
    return grey_buf;
  };
  const std::vector<std::pair<int64_t, int>> runs{{1, 2}, {5, 1}, {64, 1}};
  for (const auto& [core, threads] : runs) {
    ParticleOptions o = chunk_options(true);
    o.threads = threads;
    int64_t calls = 0, last = 0;
    const auto got = measure_particles_chunked(sh, s.labels.geometry(), labels, grey, {core, 0}, o,
                                               [&](int64_t done, int64_t nz) {
                                                 ++calls;
                                                 EXPECT_GT(done, last);
                                                 EXPECT_EQ(nz, sh.nz);
                                                 last = done;
                                               });
    EXPECT_EQ(calls, (sh.nz + core - 1) / core);
    EXPECT_EQ(got.slabs, calls);
    EXPECT_EQ(got.normal_slabs, (sh.nz + core - 1) / core);
    EXPECT_GT(got.contacts, 10);
    EXPECT_EQ(last, sh.nz);
    expect_same_tables(ref, got.particles, "core " + std::to_string(core) + ", " + std::to_string(threads) + " threads");
  }
  // Slabs as thick as a memory limit allows beside the projected lists
  // (without contacts: their normals' margin is most of this small volume).
  ParticleOptions nc = chunk_options(true);
  nc.contacts = false;
  ParticleOptions nc_whole = nc;
  nc_whole.grey = &gv;
  const auto ref_nc = measure_particles(s.labels.view(), nc_whole);
  const int64_t limit = kMeasureFixedBytes + 200000;
  const auto adaptive = measure_particles_chunked(sh, s.labels.geometry(), labels, grey, {0, limit}, nc);
  EXPECT_GT(adaptive.slabs, 2);
  EXPECT_GT(adaptive.boundary_voxels, 1000);
  expect_same_tables(ref_nc, adaptive.particles, "adaptive slabs");
  EXPECT_THROW(measure_particles_chunked(sh, s.labels.geometry(), labels, grey, {0, kMeasureFixedBytes + 20000}, nc),
               UsageError);
  // The oriented box sees the same points in the same order.
  ParticleOptions boxed = chunk_options(true, true);
  boxed.grey = &gv;
  boxed.threads = 1;  // the box's cost varies 100-fold per particle: a second thread mostly waits
  const auto ref_box = measure_particles(s.labels.view(), boxed);
  boxed.grey = nullptr;
  expect_same_tables(ref_box, measure_particles_chunked(sh, s.labels.geometry(), labels, grey, {3, 0}, boxed).particles,
                     "box");
  // Without the grey scan: the label volumes.
  const auto ref_plain = measure_particles(s.labels.view(), chunk_options(false));
  const auto plain = measure_particles_chunked(sh, s.labels.geometry(), labels, {}, {3, 0}, chunk_options(false));
  expect_same_tables(ref_plain, plain.particles, "no grey scan");
  EXPECT_LT(plain.particles[0].grey_volume_m3, 0.0);
}

// The contact search by slabs: every contact of find_contacts, every number
// equal (crossings are integer sums; each normal's ball is read whole from a
// slab with the ball's margin).
TEST(MeasureChunked, ContactSearchBySlabsIsFindContacts) {
  const ChunkScene s = chunk_scene(11);
  const Shape sh = s.labels.shape();
  ContactOptions co;
  co.normal_radius_voxels = 4;  // a ball of a few slices: slabs thinner than it
  const ContactResult ref = find_contacts(s.labels.view(), co);
  ASSERT_GE(ref.contacts.size(), 10u);
  auto window = [&](int64_t w0, int64_t w1) { return chunk_slices(s.labels, w0, w1 - w0); };
  for (const int64_t core : {int64_t(1), int64_t(7)}) {
    ContactSearch search(sh, s.labels.geometry(), co);
    for (int64_t c0 = 0; c0 < sh.nz; c0 += core) {
      const int64_t c1 = std::min(sh.nz, c0 + core), w0 = std::max<int64_t>(0, c0 - kCrossingMarginBelow);
      const Volume<uint32_t> v = window(w0, c1);
      search.add_crossings(v.view(), c0 - w0, c1 - w0, w0);
    }
    EXPECT_THROW(search.result(), UsageError);  // no normals yet
    const int64_t m = search.ball_margin();
    for (int64_t c0 = 0; c0 < sh.nz; c0 += core) {
      const int64_t c1 = std::min(sh.nz, c0 + core);
      const int64_t w0 = std::max<int64_t>(0, c0 - m), w1 = std::min(sh.nz, c1 + m);
      const Volume<uint32_t> v = window(w0, w1);
      if (c0 == 0 && w1 > 1) {  // a window short of the ball's margin is refused
        const Volume<uint32_t> thin = window(0, c1);
        if (c1 < sh.nz) EXPECT_THROW(search.add_normals(thin.view(), 0, c1, 0), UsageError);
      }
      search.add_normals(v.view(), c0 - w0, c1 - w0, w0);
    }
    const ContactResult got = search.result();
    ASSERT_EQ(got.contacts.size(), ref.contacts.size()) << "core " << core;
    for (size_t c = 0; c < ref.contacts.size(); ++c) {
      const Contact &a = ref.contacts[c], &b = got.contacts[c];
      EXPECT_EQ(a.a, b.a);
      EXPECT_EQ(a.b, b.b);
      EXPECT_EQ(a.area_m2, b.area_m2);
      EXPECT_EQ(a.normal, b.normal);
      EXPECT_EQ(a.point_m, b.point_m);
      EXPECT_EQ(a.crossings, b.crossings);
      EXPECT_EQ(a.axis, b.axis);
      EXPECT_EQ(a.face_to_face, b.face_to_face);
    }
  }
}

TEST(MeasureChunked, PlanAndRefusals) {
  const Shape sh{2048, 2048, 2048};
  const MeasureChunkPlan none = plan_measure_chunks(sh, GreyHeld::whole, 0);
  EXPECT_TRUE(none.in_memory);
  const int64_t gib = int64_t(1) << 30;
  const MeasureChunkPlan p = plan_measure_chunks(sh, GreyHeld::whole, 16 * gib);
  EXPECT_FALSE(p.in_memory);
  EXPECT_GE(p.core, 1);
  // The first slab and the planned lists fit under the limit.
  EXPECT_LE(double(p.list_bytes) + double(p.core + 2) * 6.0 * double(sh.slice_voxels()) + double(kMeasureFixedBytes),
            double(16 * gib));
  EXPECT_GT(double(p.estimate_bytes), 7.0 * double(sh.voxels()));  // labels + grey + lists
  EXPECT_THROW(plan_measure_chunks(sh, GreyHeld::whole, 4 * gib), UsageError);  // the lists alone need ~10 GB
  EXPECT_THROW(plan_measure_chunks({10, 10, 70000}, GreyHeld::none, 1), UsageError);  // over 65535 a side
  // A grey scan read slab by slab costs its window, not 2 B/voxel: 1024^3
  // labels (5 GiB + 128 MiB) with a uint16 HDF5 scan fit under 5.5 GiB,
  // with the scan held whole (7 GiB) they do not.
  const Shape k{1024, 1024, 1024};
  const MeasureChunkPlan slabs = plan_measure_chunks(k, GreyHeld::slabs, 11 * gib / 2);
  EXPECT_TRUE(slabs.in_memory);
  EXPECT_EQ(slabs.estimate_bytes, 5 * k.voxels() + 2 * grey_window_slices(k) * k.slice_voxels() + kMeasureFixedBytes);
  EXPECT_FALSE(plan_measure_chunks(k, GreyHeld::whole, 11 * gib / 2).in_memory);
  EXPECT_EQ(plan_measure_chunks(k, GreyHeld::none, 0).estimate_bytes, 5 * k.voxels() + kMeasureFixedBytes);
  const Shape small{10, 10, 10};
  auto none_read = [](int64_t, int64_t) -> Volume<uint32_t> { return {}; };
  ParticleOptions o;
  o.surface = true;
  Geometry g;
  g.voxel_size_m = {1e-5, 1e-5, 1e-5};
  EXPECT_THROW(measure_particles_chunked(small, g, none_read, {}, {2, 0}, o), UsageError);
  o.surface = false;
  EXPECT_THROW(measure_particles_chunked(small, g, none_read, {}, {0, 0}, o), UsageError);
  EXPECT_THROW(measure_particles_chunked(small, Geometry{}, none_read, {}, {2, 0}, o), UsageError);
  // A reader that returns the wrong shape: InputError naming the slices.
  EXPECT_THROW(measure_particles_chunked(small, g, none_read, {}, {4, 0}, o), InputError);
}

}  // namespace
}  // namespace tg::measure
